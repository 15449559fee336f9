// Bounded reads of Common/InputFiles.h (issue 34): a path that is not a
// regular file (FIFO, character device, directory, through a symlink too) is
// refused before it is opened, a file larger than a quarter of the memory
// limit is refused by its size, and a good file is read whole.

#include "InputFiles.h"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

namespace
{
using namespace translucency;
namespace fs = std::filesystem;

std::string MessageOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const Error& e)
  {
    return e.what();
  }
  return "(no error)";
}

bool Contains(const std::string& text, const std::string& part)
{
  return text.find(part) != std::string::npos;
}

class InputFiles : public ::testing::Test
{
protected:
  void SetUp() override
  {
    Dir = fs::temp_directory_path() / ("translucency-input-files-" + std::to_string(getpid()));
    fs::create_directories(Dir);
  }
  void TearDown() override
  {
    SetDefaultMemoryLimit(std::size_t(8) << 30);
    fs::remove_all(Dir);
  }
  fs::path Dir;
};

TEST_F(InputFiles, RefusesWhatIsNotARegularFile)
{
  const std::string fifo = (Dir / "mesh.vtu").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::string m = MessageOf([&] { ReadInputFile(fifo, "mesh file"); }); // must not block
  EXPECT_TRUE(Contains(m, "mesh file '" + fifo + "' is a FIFO (named pipe), not a regular file"))
    << m;
  const std::string zero = (Dir / "material.json").string();
  fs::create_symlink("/dev/zero", zero);
  m = MessageOf([&] { CheckInputFile(zero, "material file"); });
  EXPECT_TRUE(Contains(m, "is a character device, not a regular file")) << m;
  m = MessageOf([&] { CheckInputFile(Dir.string(), "scene file"); });
  EXPECT_TRUE(Contains(m, "is a directory")) << m;
  m = MessageOf([&] { CheckInputFile((Dir / "missing.json").string(), "paint file"); });
  EXPECT_TRUE(Contains(m, "paint file '")) << m;
  EXPECT_TRUE(Contains(m, "cannot open it: no such file")) << m;
}

TEST_F(InputFiles, SizeBoundFollowsTheMemoryLimit)
{
  const std::string path = (Dir / "big.vtu").string();
  {
    std::ofstream out(path, std::ios::binary);
    out << std::string(5000, 'x');
  }
  EXPECT_EQ(MaxInputFileBytes(), std::uintmax_t(2) << 30); // a quarter of 8 GiB
  EXPECT_EQ(ReadInputFile(path, "mesh file"), std::string(5000, 'x'));
  SetDefaultMemoryLimit(16000); // a quarter: 4000 bytes
  const std::string m = MessageOf([&] { ReadInputFile(path, "mesh file"); });
  EXPECT_TRUE(Contains(m, "holds 0.00477 MiB (5000 bytes)")) << m;
  EXPECT_TRUE(Contains(m, "--memory-limit")) << m;
  SetDefaultMemoryLimit(20000);
  EXPECT_EQ(CheckInputFile(path, "mesh file"), 5000u);
}

} // namespace
