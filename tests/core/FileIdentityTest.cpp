#include <regolith/core/Error.hpp>
#include <regolith/core/FileIdentity.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using regolith::core::pathProblem;
using regolith::core::refuseOverwritingInput;
using regolith::core::sameFile;

namespace {

/// A fresh folder of this test process, with a file `input` (content "in") in it.
class FileIdentityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("regolith_identity_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::ofstream(input()) << "in";
  }
  void TearDown() override { fs::remove_all(dir_); }
  [[nodiscard]] fs::path input() const { return dir_ / "input.tif"; }
  [[nodiscard]] fs::path at(const std::string& name) const { return dir_ / name; }

  /// The message refuseOverwritingInput() throws for `output`, or "" if it accepts it.
  [[nodiscard]] std::string refusal(const fs::path& output) const {
    const std::vector<fs::path> inputs{at("other.h5"), input()};
    try {
      refuseOverwritingInput(output, inputs, "import");
    } catch (const regolith::InvalidArgument& e) {
      return e.what();
    }
    return "";
  }

 private:
  fs::path dir_;
};

TEST_F(FileIdentityTest, RefusesTheInputItselfByEveryName) {
  const std::string expected = ": output is the same file as the input " + input().string() +
                               ", expected a file that is not one of the inputs";
  EXPECT_EQ(refusal(input()), "import: " + input().string() + expected);
  // The same file through "./", a symlink, a symlink to a symlink and a hard link.
  const fs::path dotted = input().parent_path() / "." / "input.tif";
  EXPECT_EQ(refusal(dotted), "import: " + dotted.string() + expected);
  fs::create_symlink(input(), at("link.tif"));
  EXPECT_EQ(refusal(at("link.tif")), "import: " + at("link.tif").string() + expected);
  fs::create_symlink(at("link.tif"), at("link2.tif"));
  EXPECT_EQ(refusal(at("link2.tif")), "import: " + at("link2.tif").string() + expected);
  fs::create_hard_link(input(), at("hard.tif"));
  EXPECT_EQ(refusal(at("hard.tif")), "import: " + at("hard.tif").string() + expected);
  EXPECT_TRUE(sameFile(at("hard.tif"), at("link.tif")));
}

TEST_F(FileIdentityTest, AcceptsNewFilesAndOtherFiles) {
  EXPECT_EQ(refusal(at("new.h5")), "");   // does not exist yet
  std::ofstream(at("copy.tif")) << "in";  // same content, another file
  EXPECT_EQ(refusal(at("copy.tif")), "");
  EXPECT_FALSE(sameFile(at("copy.tif"), input()));
  fs::create_symlink(at("missing.h5"), at("dangling.h5"));  // writing it creates its target
  EXPECT_EQ(refusal(at("dangling.h5")), "");
  EXPECT_FALSE(sameFile(at("missing.h5"), at("missing.h5")));
}

TEST_F(FileIdentityTest, NamesSymlinkLoopsAndDanglingLinks) {
  fs::create_symlink(at("b"), at("a"));
  fs::create_symlink(at("a"), at("b"));
  EXPECT_EQ(pathProblem(at("a")), "symlink loop (too many levels of symbolic links)");
  fs::create_symlink(at("gone.h5"), at("dangling.h5"));
  EXPECT_EQ(pathProblem(at("dangling.h5")),
            "dangling symlink (its target " + at("gone.h5").string() + " does not exist)");
  EXPECT_EQ(pathProblem(at("nothing.h5")), "no such file");
  EXPECT_EQ(pathProblem(input() / "x.h5"), "a part of the path is not a folder");
  EXPECT_EQ(pathProblem(input()), std::nullopt);
  // An output that is a symlink loop is refused with the loop named, not written through.
  try {
    refuseOverwritingInput(at("a"), {}, "render");
    ADD_FAILURE() << "a symlink loop as output was accepted";
  } catch (const regolith::IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              "render: " + at("a").string() + ": symlink loop (too many levels of symbolic links)");
  }
}

}  // namespace
