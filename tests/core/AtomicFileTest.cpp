#include <regolith/core/AtomicFile.hpp>
#include <regolith/core/Error.hpp>

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <thread>
#include <vector>

// Every fsync() of this test program, counted, then done by the C library's own (interposed:
// the executable's definition binds the static core library's calls; the syscall still runs).
namespace {
std::atomic<int> gFsyncCalls{0};
}  // namespace

extern "C" int fsync(int fd) {
  using Fn = int (*)(int);
  static const auto real =
      reinterpret_cast<Fn>(  // NOLINT(cppcoreguidelines-pro-type-reinterpret-cast)
          dlsym(RTLD_NEXT, "fsync"));
  gFsyncCalls.fetch_add(1);
  return real(fd);
}

namespace fs = std::filesystem;
using regolith::core::Durability;
using regolith::core::temporaryPathFor;
using regolith::core::writeFileAtomically;
using regolith::core::writeStreamAtomically;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("regolith_core_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

std::string bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Files in the folder of `p` whose names start with p's name (the target and temporaries).
std::vector<std::string> siblings(const fs::path& p) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(p.parent_path())) {
    const std::string n = e.path().filename().string();
    if (n.rfind(p.filename().string(), 0) == 0) out.push_back(n);
  }
  return out;
}

}  // namespace

TEST(AtomicFile, WritesTheContentUnderTheTargetAndLeavesNoTemporary) {
  const fs::path p = scratch("a.txt");
  writeStreamAtomically(
      p, [](std::ostream& o) { o << "first"; }, "test()");
  EXPECT_EQ(bytes(p), "first");
  writeStreamAtomically(
      p, [](std::ostream& o) { o << "second, longer"; }, "test()");
  EXPECT_EQ(bytes(p), "second, longer");
  EXPECT_EQ(siblings(p), std::vector<std::string>{"a.txt"});
}

TEST(AtomicFile, ADurableWriteSyncsTheFileAndTheFolderAndAScratchWriteNeither) {
  const fs::path target = scratch("durability.bin");
  const auto writeText = [](const std::string& text) {
    return [text](const fs::path& tmp) { std::ofstream(tmp, std::ios::binary) << text; };
  };
  int before = gFsyncCalls.load();
  writeFileAtomically(target, writeText("durable"), "test");
  EXPECT_EQ(gFsyncCalls.load() - before, 2);  // the temporary, then the folder
  EXPECT_EQ(bytes(target), "durable");

  before = gFsyncCalls.load();
  writeFileAtomically(target, writeText("scratch"), "test", Durability::Scratch);
  EXPECT_EQ(gFsyncCalls.load() - before, 0);
  // Still renamed into place whole, with no temporary left.
  EXPECT_EQ(bytes(target), "scratch");
  EXPECT_EQ(siblings(target), std::vector<std::string>{"durability.bin"});
  fs::remove(target);
}

TEST(AtomicFile, AWriterThatThrowsLeavesThePreviousContentAndNoTemporary) {
  const fs::path p = scratch("b.txt");
  writeStreamAtomically(
      p, [](std::ostream& o) { o << "previous"; }, "test()");
  fs::path seen;
  EXPECT_THROW(writeFileAtomically(
                   p,
                   [&](const fs::path& tmp) {
                     seen = tmp;
                     std::ofstream(tmp) << "half";
                     throw std::runtime_error("writer failed");
                   },
                   "test()"),
               std::runtime_error);
  EXPECT_EQ(bytes(p), "previous");
  EXPECT_FALSE(fs::exists(seen));
  EXPECT_EQ(siblings(p), std::vector<std::string>{"b.txt"});
}

TEST(AtomicFile, TemporaryNamesAreUniqueAndBesideTheTarget) {
  const fs::path p = scratch("c.h5");
  const fs::path a = temporaryPathFor(p);
  const fs::path b = temporaryPathFor(p);
  EXPECT_NE(a, b);
  EXPECT_EQ(a.parent_path(), p.parent_path());
  const std::string prefix = "c.h5.tmp-" + std::to_string(::getpid()) + "-";
  EXPECT_EQ(a.filename().string().rfind(prefix, 0), 0U) << a;

  // Many threads writing one target at once: each write is whole, none collides.
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&p, t] {
      for (int i = 0; i < 20; ++i) {
        writeStreamAtomically(
            p, [&](std::ostream& o) { o << std::string(1000, static_cast<char>('a' + t)); },
            "test()");
      }
    });
  }
  for (std::thread& t : threads) t.join();
  const std::string last = bytes(p);
  ASSERT_EQ(last.size(), 1000U);
  EXPECT_EQ(std::set<char>(last.begin(), last.end()).size(), 1U);
  EXPECT_EQ(siblings(p), std::vector<std::string>{"c.h5"});
}

TEST(AtomicFile, FileSystemFailuresAreIoErrorsNamingOperationAndFile) {
  // A missing folder is not created: a mistyped path is an error.
  const fs::path missing = scratch("no-such-folder") / "d.txt";
  try {
    writeStreamAtomically(
        missing, [](std::ostream& o) { o << "x"; }, "Thing::save()");
    FAIL() << "expected IoError";
  } catch (const regolith::IoError& e) {
    EXPECT_EQ(std::string(e.what()), "Thing::save(): " + missing.string() + ": the folder " +
                                         missing.parent_path().string() + " does not exist");
  }
  EXPECT_FALSE(fs::exists(missing.parent_path()));
  // A folder that is a regular file.
  const fs::path blocker = scratch("not-a-folder");
  std::ofstream(blocker) << "x";
  const fs::path p = blocker / "d.txt";
  try {
    writeStreamAtomically(
        p, [](std::ostream& o) { o << "x"; }, "Thing::save()");
    FAIL() << "expected IoError";
  } catch (const regolith::IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              "Thing::save(): " + p.string() + ": " + blocker.string() + " is not a folder");
  }
  // A writer that never creates the temporary.
  const fs::path q = scratch("e.txt");
  try {
    writeFileAtomically(
        q, [](const fs::path&) {}, "Thing::save()");
    FAIL() << "expected IoError";
  } catch (const regolith::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("the writer did not create the temporary file"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(q));
}

TEST(AtomicFile, AKilledWriterNeverLeavesAPartialTarget) {
  const fs::path p = scratch("f.bin");
  writeStreamAtomically(
      p, [](std::ostream& o) { o << "old"; }, "test()");
  for (int trial = 0; trial < 5; ++trial) {
    int ready[2];
    ASSERT_EQ(::pipe(ready), 0);
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      writeFileAtomically(
          p,
          [&](const fs::path& tmp) {
            std::ofstream out(tmp, std::ios::binary);
            out << std::string(1 << 20, 'n');
            out.flush();
            const char c = 'x';
            (void)::write(ready[1], &c, 1);
            ::pause();  // killed here, mid-write
          },
          "test()");
      ::_exit(0);
    }
    char c = 0;
    ASSERT_EQ(::read(ready[0], &c, 1), 1);
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    ::close(ready[0]);
    ::close(ready[1]);
    EXPECT_EQ(bytes(p), "old");
    for (const std::string& n : siblings(p)) {
      if (n != "f.bin") fs::remove(p.parent_path() / n);  // the killed writer's temporary
    }
  }
}
