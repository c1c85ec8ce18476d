#include "io/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <utility>

#include "error.h"
#include "platform/files.h"

namespace ndfbake {

namespace fs = std::filesystem;

namespace {

// Unique per process (pid) and per call (counter), so concurrent writers never share a temp file.
std::string temp_path_for(const std::string& final_path)
{
    static std::atomic<uint64_t> counter{0};
    const fs::path final_file = path_from_utf8(final_path);
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "." + std::string&&.
    std::string name = ".";
    name += path_to_utf8(final_file.stem());
    name += ".tmp-" + std::to_string(current_process_id()) + "-" + std::to_string(counter++);
    name += path_to_utf8(final_file.extension());
    return path_to_utf8(final_file.parent_path() / path_from_utf8(name));
}

[[noreturn]] void throw_not_writable(const std::string& dir, const std::string& reason)
{
    throw Error(Status::io_error, "output folder '" + dir + "' is not writable: " + reason);
}

}  // namespace

void write_file_atomic(const std::string& final_path,
                       const std::function<void(const std::string& temp_path)>& writer)
{
    const std::string temp_path = temp_path_for(final_path);
    const fs::path temp_file = path_from_utf8(temp_path), final_file = path_from_utf8(final_path);
    const auto remove_temp = [&] {
        std::error_code ignored;
        fs::remove(temp_file, ignored);
    };
    try {
        writer(temp_path);
        FileResult done = flush_file_to_disk(temp_file);
        if (done.ok) done = replace_file(temp_file, final_file);
        if (!done.ok) throw Error(Status::io_error, "cannot write '" + final_path + "': " + done.reason);
    } catch (const Error& e) {
        remove_temp();
        // Writers' libraries name the file they were given: the user asked for final_path.
        std::string message = e.what();
        for (size_t at = message.find(temp_path); at != std::string::npos;
             at = message.find(temp_path, at + final_path.size()))
            message.replace(at, temp_path.size(), final_path);
        throw Error(e.status(), message);
    } catch (...) {
        remove_temp();
        throw;
    }
}

void write_text_atomic(const std::string& path, const std::string& text)
{
    write_file_atomic(path, [&](const std::string& temp_path) {
        std::ofstream file(path_from_utf8(temp_path), std::ios::binary | std::ios::trunc);
        if (file)
            file.write(text.data(), std::streamsize(text.size()));
        if (file)
            file.close();
        if (!file)
            throw Error(Status::io_error, "cannot write '" + path + "': " + std::strerror(errno));
    });
}

void ensure_writable_directory(const std::string& dir)
{
    // An empty folder is the current directory, as in a bare output file name.
    const fs::path folder = dir.empty() ? fs::path(".") : path_from_utf8(dir);
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec)
        throw_not_writable(dir, ec.message());
    if (!fs::is_directory(folder, ec))
        throw_not_writable(dir, "not a directory");

    // Permission bits alone do not answer this (ACLs, read-only mounts, root): try it. The name
    // is unique per call, so two bakes into one folder from two threads do not collide on it.
    static std::atomic<uint64_t> probes{0};
    const fs::path probe = folder / (".ndfbake-write-probe-" + std::to_string(current_process_id()) + "-" +
                                     std::to_string(probes++));
    const FileResult created = create_new_file(probe);
    if (!created.ok)
        throw_not_writable(dir, created.reason);
    fs::remove(probe, ec);
}

void commit_files(const std::string& staging, const std::string& folder, const std::vector<std::string>& names,
                  const std::vector<std::string>& retired)
{
    static std::atomic<uint64_t> counter{0};
    const fs::path from_dir = path_from_utf8(staging), to_dir = path_from_utf8(folder);
    const fs::path aside = to_dir / (".ndfbake-previous-" + std::to_string(current_process_id()) + "-" +
                                     std::to_string(counter++));

    // The earlier files this replaces or retires: those of either list that exist.
    std::vector<std::string> earlier;
    std::set<std::string> seen;
    std::error_code ec;
    for (const auto* list : {&names, &retired})
        for (const std::string& name : *list)
            if (seen.insert(name).second && fs::exists(fs::symlink_status(to_dir / path_from_utf8(name), ec)))
                earlier.push_back(name);

    std::vector<std::pair<fs::path, fs::path>> done;  // every rename made, to undo on failure
    const auto move = [&](const fs::path& from, const fs::path& to, const fs::path& named) {
        const FileResult moved = replace_file(from, to);
        if (!moved.ok) throw Error(Status::io_error, "cannot write '" + path_to_utf8(named) + "': " + moved.reason);
        done.emplace_back(from, to);
    };
    try {
        if (!earlier.empty() && !fs::create_directory(aside, ec))
            throw Error(Status::io_error, "cannot write into '" + folder + "': cannot create '" +
                                              path_to_utf8(aside) + "': " + ec.message());
        for (const std::string& name : earlier) {
            const fs::path file = to_dir / path_from_utf8(name);
            move(file, aside / path_from_utf8(name), file);
        }
        for (const std::string& name : names) {
            const fs::path file = to_dir / path_from_utf8(name);
            move(from_dir / path_from_utf8(name), file, file);
        }
    } catch (const Error& e) {
        // Undone in reverse: each new file back into staging before the earlier one returns.
        // These renames reverse ones that just succeeded in the same folders, so they fail only
        // if something else changed the folder meanwhile; then the message says where the
        // earlier files are.
        std::string stranded;
        for (auto step = done.rbegin(); step != done.rend(); ++step)
            if (!replace_file(step->second, step->first).ok)
                stranded += (stranded.empty() ? "'" : ", '") + path_to_utf8(step->second) + "'";
        if (stranded.empty()) {
            fs::remove(aside, ec);
            throw;
        }
        throw Error(Status::io_error, std::string(e.what()) + "; and these could not be moved back: " + stranded);
    }
    // The earlier files. A failure here (Windows: a retired file still open in another program)
    // leaves a hidden folder behind, not a failed commit.
    fs::remove_all(aside, ec);
}

std::vector<std::string> missing_folders(const std::string& dir)
{
    std::vector<std::string> missing;
    std::error_code ec;
    fs::path folder = path_from_utf8(dir).lexically_normal();
    if (!folder.has_filename()) folder = folder.parent_path();  // a trailing separator
    for (; !folder.empty() && !fs::exists(folder, ec); folder = folder.parent_path()) {
        missing.push_back(path_to_utf8(folder));
        if (folder == folder.parent_path()) break;
    }
    return missing;
}

void remove_empty_folders(const std::vector<std::string>& folders)
{
    std::error_code ec;
    for (const std::string& folder : folders)
        fs::remove(path_from_utf8(folder), ec);  // removes only an empty folder
}

}  // namespace ndfbake
