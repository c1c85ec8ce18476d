// Writing output files so that a reader (Blender, a second bake) never sees a half-written file:
// everything is written to a temporary sibling and renamed over the final path in one step.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace ndfbake {

// Every path here is UTF-8 (platform/files.h).

// Runs `writer` on a temporary path in final_path's directory, named
// ".<stem>.tmp-<pid>-<counter><extension>" so format-by-extension writers still work, flushes it
// to disk and renames it onto final_path. If anything throws, the temporary file is removed, the
// exception propagates and final_path is left as it was. A final_path that another program holds
// open (Windows refuses to replace it) fails with Error(io_error) saying so.
void write_file_atomic(const std::string& final_path,
                       const std::function<void(const std::string& temp_path)>& writer);

// Atomically replaces `path` with `text`. Throws Error(io_error) on failure.
void write_text_atomic(const std::string& path, const std::string& text);

// Creates `dir` (and its parents) if missing and proves it writable by creating and removing a
// probe file. Throws Error(io_error, "output folder '<dir>' is not writable: <reason>").
void ensure_writable_directory(const std::string& dir);

// Moves the files `names` from the folder `staging` into `folder` as one change, replacing files of
// the same names there, and removes the files `retired` from `folder` (an earlier run's files this
// one does not write). All or nothing: the files to be replaced or retired are first moved aside
// (into a hidden folder in `folder`, on the same volume), then the new ones moved in; if any step
// fails (on Windows: a file open in another program), the steps done are undone in reverse, so
// `folder` holds its earlier files again, and Error(io_error) names the file and why. The new
// files that were moved back stay in `staging`.
void commit_files(const std::string& staging, const std::string& folder, const std::vector<std::string>& names,
                  const std::vector<std::string>& retired);

// `dir` and those of its parents that do not exist, innermost first: what
// ensure_writable_directory(dir) would create.
std::vector<std::string> missing_folders(const std::string& dir);
// Removes each of `folders` that is empty, in order (missing_folders' order: a parent after its child).
void remove_empty_folders(const std::vector<std::string>& folders);

// Runs `body`; if it throws, removes the folders of `dir` that were missing before (where they
// are empty again), so that a failed or cancelled run leaves no folder behind either.
template <typename Body>
decltype(auto) removing_new_folders_on_failure(const std::string& dir, Body&& body)
{
    const std::vector<std::string> missing = missing_folders(dir);
    try {
        return body();
    } catch (...) {
        remove_empty_folders(missing);
        throw;
    }
}

}  // namespace ndfbake
