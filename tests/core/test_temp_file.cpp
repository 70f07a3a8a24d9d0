// An interrupt removes the temporaries being written and still ends the process by its signal;
// files that are not (or no longer) registered stay. Each case runs in a forked child that
// interrupts itself, so the test process keeps its own handlers.
#include "core/temp_file.h"
#include "test_util.h"
#include <gtest/gtest.h>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <sys/wait.h>
#include <unistd.h>

using namespace lpt;
namespace fs = std::filesystem;

namespace {

void touch(const std::string& path) { ::close(::open(path.c_str(), O_CREAT | O_WRONLY, 0644)); }

}  // namespace

TEST(TemporaryFile, AnInterruptRemovesTheRegisteredOnesAndEndsByItsSignal) {
    const std::string dir = test::temp_dir("temp-file");
    const std::string writing = dir + "/.out.tmp.exr", kept = dir + "/other.exr", done = dir + "/.done.tmp.exr";
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {  // only system calls and the class under test below: the parent may hold locks
        remove_temporaries_on_interrupt();
        touch(writing);
        touch(kept);
        touch(done);
        { const TemporaryFile finished(done); }  // renamed and released before the interrupt
        const TemporaryFile in_progress(writing);
        std::raise(SIGINT);
        ::_exit(0);  // not reached: the default action ends the process
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status)) << "exit status " << status;
    EXPECT_EQ(WTERMSIG(status), SIGINT);
    EXPECT_FALSE(fs::exists(writing)) << "the interrupted write's temporary stayed";
    EXPECT_TRUE(fs::exists(kept));
    EXPECT_TRUE(fs::exists(done)) << "a released registration was removed";
}

// nohup ignores SIGHUP for the process it starts: installing the handler must not undo that.
TEST(TemporaryFile, AnIgnoredSignalStaysIgnored) {
    const std::string dir = test::temp_dir("temp-file-ignored");
    const std::string writing = dir + "/.out.tmp.exr";
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        std::signal(SIGHUP, SIG_IGN);
        remove_temporaries_on_interrupt();
        touch(writing);
        const TemporaryFile in_progress(writing);
        std::raise(SIGHUP);
        ::_exit(3);  // reached: the hang-up was ignored
    }
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFEXITED(status)) << "the ignored SIGHUP ended the process";
    EXPECT_EQ(WEXITSTATUS(status), 3);
    EXPECT_TRUE(fs::exists(writing));
}
