// Output files are whole or absent (hemo/io/atomic_file.hpp).
#include "hemo/io/atomic_file.hpp"

#include "file_bytes.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

namespace hemo::test {
namespace {

namespace fs = std::filesystem;

fs::path freshDir(const std::string& name) { return freshTempDir("atomic_" + name); }

std::size_t entries(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++n;
  return n;
}

TEST(AtomicFile, CommitPutsTheWholeFileUnderItsNameAndNothingElse) {
  const fs::path dir = freshDir("commit");
  {
    io::AtomicFile file(dir / "out.txt");
    file.stream() << "first line\n" << 42 << '\n';
    EXPECT_FALSE(fs::exists(dir / "out.txt")) << "nothing under the real name before the commit";
    file.commit();
  }
  EXPECT_EQ(readText(dir / "out.txt"), "first line\n42\n");
  EXPECT_EQ(entries(dir), 1u) << "no temporary left";
  fs::remove_all(dir);
}

TEST(AtomicFile, UnfinishedFileLeavesTheOldOneAndNoTemporary) {
  const fs::path dir = freshDir("unfinished");
  { std::ofstream(dir / "summary.json") << "{\"old\": true}\n"; }
  try {
    io::AtomicFile file(dir / "summary.json");
    file.stream() << "{\"new\": ";
    throw std::runtime_error("stopped half way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(readText(dir / "summary.json"), "{\"old\": true}\n");
  EXPECT_EQ(entries(dir), 1u);
  fs::remove_all(dir);
}

TEST(AtomicFile, CFileWritesCommitToo) {
  const fs::path dir = freshDir("cfile");
  {
    io::AtomicFile file(dir / "frame.png");
    ASSERT_EQ(std::fwrite("\x89PNG", 1, 4, file.file()), 4u);
    file.commit();
  }
  EXPECT_EQ(readText(dir / "frame.png"), "\x89PNG");
  fs::remove_all(dir);
}

TEST(AtomicFile, UnwritableDirectoryIsAWriteErrorNamingTheFile) {
  const fs::path path = fs::temp_directory_path() / "hemo_no_such_dir_for_atomic_file" / "x.vtk";
  try {
    io::AtomicFile file(path);
    ADD_FAILURE() << "expected a WriteError";
  } catch (const io::WriteError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hemo::test
