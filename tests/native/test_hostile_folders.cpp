// Output folders that cannot take a bake, through the public C API (issue 6): a path that cannot be
// a folder, read-only folders and full ones. Each gets a specific status and a one-line message,
// and a failed bake leaves the folder as it was (an earlier bake's files untouched).
//
// Read-only and full folders are simulated in a forked child so the test process is untouched:
// - read-only: a tmpfs mounted read-only in a private mount namespace (EROFS) where the sandbox
//   allows mount(2), and a folder without write permission (EACCES), as root without
//   CAP_DAC_OVERRIDE (root ignores permission bits);
// - full: RLIMIT_FSIZE makes every write past the limit fail with EFBIG, exactly as a full disk
//   fails a write (portable, needs no privilege); and a small tmpfs (ENOSPC) where mount(2) works.

#include <gtest/gtest.h>

#include "hostile_fixtures.h"

namespace ndfbake {
namespace {

using namespace hostile_inputs;

// ---- child processes -------------------------------------------------------------------------

// What a child reports: a status (or kSkipped) and a message.
struct ChildReport {
    int status = -1;
    std::string message;
};
constexpr int kSkipped = -2;

// A bake run in a child process, in the conditions `setup` creates there (rlimits, a mount
// namespace, another user). The child is this test binary started afresh (fork, setup, exec), so
// it inherits no threads: a forked copy of a process whose OpenEXR thread pool is running would
// hang on its first EXR. It bakes `earlier` (if any) into `out` first, then `input`, and reports
// the second bake's status and message, flagging any change the failed bake made to the folder.
// `setup` runs between fork and exec, so it allocates nothing: it returns null, or the name of the
// step that failed (errno tells why), which makes the child report kSkipped.
ChildReport bake_in_child(const std::function<const char*()>& setup, const std::string& input,
                          const std::string& out, const std::string& earlier = {})
{
    int fds[2];
    if (::pipe(fds) != 0) return {-1, "pipe failed"};
    // Everything the child needs, built before fork: after it only system calls are made.
    std::vector<std::string> env_strings = {"NDFB_CHILD_FD=" + std::to_string(fds[1]), "NDFB_CHILD_INPUT=" + input,
                                            "NDFB_CHILD_OUT=" + out, "NDFB_CHILD_EARLIER=" + earlier};
    for (char** e = environ; *e; ++e) env_strings.emplace_back(*e);
    std::vector<char*> envp;
    for (std::string& e : env_strings) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::string exe = "/proc/self/exe", filter = "--gtest_filter=HostileChild.DISABLED_Bake",
                disabled = "--gtest_also_run_disabled_tests";
    char* argv[] = {exe.data(), filter.data(), disabled.data(), nullptr};

    const pid_t pid = ::fork();
    if (pid == 0) {
        ::close(fds[0]);
        if (const char* failed = setup()) {
            char payload[256];
            const int n = std::snprintf(payload, sizeof payload, "%d\n%s: %s", kSkipped, failed, std::strerror(errno));
            ssize_t written = ::write(fds[1], payload, size_t(std::max(0, std::min(n, int(sizeof payload) - 1))));
            (void)written;
            ::_exit(0);
        }
        const int null = ::open("/dev/null", O_WRONLY);
        if (null >= 0) ::dup2(null, STDOUT_FILENO);
        ::execve(argv[0], argv, envp.data());
        ::_exit(127);
    }
    ::close(fds[1]);
    std::string payload;
    char buffer[512];
    for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;) payload.append(buffer, size_t(n));
    ::close(fds[0]);
    int wait_status = 0;
    ::waitpid(pid, &wait_status, 0);
    const size_t newline = payload.find('\n');
    if (!WIFEXITED(wait_status) || WEXITSTATUS(wait_status) != 0 || newline == std::string::npos)
        return {-1, "child failed (wait status " + std::to_string(wait_status) + "): " + payload};
    return {std::stoi(payload.substr(0, newline)), payload.substr(newline + 1)};
}

// The child's side: does nothing unless started by bake_in_child.
TEST(HostileChild, DISABLED_Bake)
{
    const char* fd = std::getenv("NDFB_CHILD_FD");
    if (!fd) GTEST_SKIP() << "run by the hostile-input tests in a child process";
    const std::string input = std::getenv("NDFB_CHILD_INPUT"), out = std::getenv("NDFB_CHILD_OUT"),
                      earlier = std::getenv("NDFB_CHILD_EARLIER");
    ndfb_context ctx = nullptr;
    ASSERT_EQ(ndfb_context_create(&ctx), NDFB_OK);
    ndfb_fit_options fit;
    ndfb_fit_options_init(&fit);
    fit.max_lobes = 2;
    fit.threads = 2;
    std::string problems;
    std::set<std::string> before;
    std::string report;
    if (!earlier.empty()) {
        if (ndfb_bake(ctx, earlier.c_str(), out.c_str(), nullptr, &fit, nullptr, nullptr, nullptr, nullptr) != NDFB_OK)
            problems += std::string(" [the earlier bake failed: ") + ndfb_last_error(ctx) + "]";
        before = entries(out);
        report = read_bytes(out + "/report.json");
    }
    const ndfb_status status = ndfb_bake(ctx, input.c_str(), out.c_str(), nullptr, &fit, nullptr, nullptr, nullptr, nullptr);
    std::string message = ndfb_last_error(ctx);
    if (entries(out) != before) message += " [the folder's files changed]";
    if (!earlier.empty() && read_bytes(out + "/report.json") != report) message += " [the earlier report changed]";
    const std::string payload = std::to_string(int(status)) + "\n" + message + problems;
    ssize_t written = ::write(std::atoi(fd), payload.data(), payload.size());
    (void)written;
    ndfb_context_destroy(ctx);
}

// In the child: a private mount namespace with a tmpfs at `dir`; the failed step where mount is
// not allowed (no CAP_SYS_ADMIN, a container that forbids it).
const char* mount_private_tmpfs(const std::string& dir, const char* options, unsigned long flags)
{
    if (::unshare(CLONE_NEWNS) != 0) return "unshare(CLONE_NEWNS)";
    if (::mount("none", "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) return "mount --make-rprivate /";
    if (::mount("ndfbake-test", dir.c_str(), "tmpfs", flags, options) != 0) return "mount tmpfs";
    return nullptr;
}

// ---- output folders --------------------------------------------------------------------------

TEST_F(HostileInputs, AnOutputPathThatCannotBeAFolderIsAnIoError)
{
    const std::string input = synth_png("in.png", 16);
    const std::string under_file = input + "/out";
    expect_error(ndfb_bake(ctx_, input.c_str(), under_file.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_ERROR_IO,
                 {"output folder '" + under_file + "' is not writable"}, "folder under a file");
    expect_error(ndfb_bake(ctx_, input.c_str(), input.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_ERROR_IO,
                 {"output folder '" + input + "' is not writable"}, "folder is a file");
    EXPECT_EQ(read_bytes(input).substr(1, 3), "PNG");  // untouched
}

TEST_F(HostileInputs, AReadOnlyOutputFolderIsAnIoErrorAndNothingIsWritten)
{
    const std::string input = synth_png("in.png", 16);
    const std::string locked = path("locked");
    fs::create_directories(locked);

    // Permission bits (EACCES). Root passes them through CAP_DAC_OVERRIDE, so as root the child
    // drops that capability from its bounding set (kept across exec, and the test binary stays
    // reachable whatever the permissions of the folders above it); without CAP_SETPCAP it becomes
    // user nobody instead.
    ::chmod(locked.c_str(), 0555);
    const bool root = ::geteuid() == 0;
    ChildReport r = bake_in_child(
        [root]() -> const char* {
            if (!root) return nullptr;
            if (::prctl(PR_CAPBSET_DROP, CAP_DAC_OVERRIDE, 0, 0, 0) == 0 &&
                ::prctl(PR_CAPBSET_DROP, CAP_DAC_READ_SEARCH, 0, 0, 0) == 0 &&
                ::prctl(PR_CAPBSET_DROP, CAP_FOWNER, 0, 0, 0) == 0)
                return nullptr;
            if (::setgid(testing_support::kNobodyGid) != 0 || ::setuid(testing_support::kNobodyUid) != 0)
                return "drop CAP_DAC_OVERRIDE or become user nobody";
            return nullptr;
        },
        input, locked + "/out");
    ::chmod(locked.c_str(), 0755);
    EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
    EXPECT_NE(r.message.find("output folder '" + locked + "/out' is not writable: Permission denied"),
              std::string::npos)
        << r.message;
    EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;
    EXPECT_TRUE(listing(locked).empty());

    // A read-only file system (EROFS), where this sandbox allows mount(2).
    const std::string ro = path("ro");
    fs::create_directories(ro);
    r = bake_in_child([&] { return mount_private_tmpfs(ro, "size=1m", MS_RDONLY); }, input, ro);
    if (r.status == kSkipped) {
        std::printf("read-only tmpfs not tested here: %s\n", r.message.c_str());
    } else {
        EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
        EXPECT_NE(r.message.find("output folder '" + ro + "' is not writable: Read-only file system"),
                  std::string::npos)
            << r.message;
        EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;
    }
}

TEST_F(HostileInputs, AFullOutputFolderIsAnIoErrorAndKeepsTheEarlierBake)
{
    // An earlier bake of a 2 x 2 map fits; the 128 x 128 bake after it does not.
    const std::string small = synth_png("small.png", 2), large = synth_png("large.png", 128);

    // Every write past 16 KiB fails with EFBIG, as on a full disk (SIGXFSZ ignored, so the write
    // returns the error instead of killing the process).
    const std::string out = path("out");
    ChildReport r = bake_in_child(
        []() -> const char* {
            ::signal(SIGXFSZ, SIG_IGN);
            const struct rlimit limit {16 * 1024, 16 * 1024};
            return ::setrlimit(RLIMIT_FSIZE, &limit) != 0 ? "setrlimit(RLIMIT_FSIZE)" : nullptr;
        },
        large, out, small);
    EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
    EXPECT_NE(r.message.find("cannot write '" + out), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("File too large"), std::string::npos) << r.message;
    EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;

    // A real ENOSPC: a 64 KiB tmpfs, where this sandbox allows mount(2).
    const std::string tiny = path("tiny");
    fs::create_directories(tiny);
    r = bake_in_child([&] { return mount_private_tmpfs(tiny, "size=64k", 0); }, large, tiny + "/out", small);
    if (r.status == kSkipped) {
        std::printf("full tmpfs not tested here: %s\n", r.message.c_str());
    } else {
        EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
        EXPECT_NE(r.message.find("cannot write '" + tiny + "/out"), std::string::npos) << r.message;
        EXPECT_NE(r.message.find("No space left on device"), std::string::npos) << r.message;
        EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;
    }
}

}  // namespace
}  // namespace ndfbake
