/**
 * @file InputFiles.h
 * @brief Bounded reads of the files a user names: every reader and loader
 * that reads a whole file into memory (VTK XML meshes, JSON materials,
 * tables, paint and stroke files, scenes, measured CSV) first checks that the
 * path names a regular file (a FIFO, /dev/zero, a terminal or a directory,
 * directly or through a symlink, could be read without end) and that its size
 * fits the memory limit (ResourceLimits.h), then reads at most that many bytes.
 */
#pragma once

#include "Error.h"
#include "ResourceLimits.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace translucency
{

/// The largest input file read whole into memory, bytes: a quarter of the
/// memory limit (GetDefaultMemoryLimit, `--memory-limit`), since parsing
/// holds the text and what is built from it (e.g. 2 GiB of the default 8 GiB).
inline std::uintmax_t MaxInputFileBytes()
{
  return static_cast<std::uintmax_t>(GetDefaultMemoryLimit() / 4);
}

/**
 * Check `path` before reading it: it must exist and be (after symlinks) a
 * regular file of at most MaxInputFileBytes(). Returns its size. Throws
 * Error "<what> '<path>': <reason>" otherwise, before anything is opened (so
 * a FIFO without a writer does not block).
 */
inline std::uintmax_t CheckInputFile(const std::string& path, const std::string& what)
{
  namespace fs = std::filesystem;
  const std::string name = what + " '" + path + "'";
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status))
  {
    throw Error(name + ": cannot open it: no such file" +
      (ec ? " (" + ec.message() + ")" : std::string()));
  }
  if (!fs::is_regular_file(status))
  {
    const char* kind = fs::is_directory(status) ? "a directory"
      : fs::is_fifo(status)                     ? "a FIFO (named pipe)"
      : fs::is_character_file(status)           ? "a character device"
      : fs::is_block_file(status)               ? "a block device"
      : fs::is_socket(status)                   ? "a socket"
                                                : "not a regular file";
    throw Error(name + " is " + kind +
      ", not a regular file: refused (it could be read without end)");
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec)
  {
    throw Error(name + ": cannot read its size (" + ec.message() + ")");
  }
  if (size > MaxInputFileBytes())
  {
    throw Error(name + " holds " + FormatBytes(static_cast<double>(size)) +
      "; inputs are read into memory and may hold at most a quarter of the memory limit, " +
      FormatBytes(static_cast<double>(MaxInputFileBytes())) + " (" + MemoryLimitOverride() + ")");
  }
  return size;
}

/// The whole of `path` after CheckInputFile(path, what): at most the size
/// checked (a file growing meanwhile is cut there). Throws Error if it cannot be opened.
inline std::string ReadInputFile(const std::string& path, const std::string& what)
{
  const std::uintmax_t size = CheckInputFile(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in)
  {
    throw Error("cannot open " + what + " '" + path + "'");
  }
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(&text[0], static_cast<std::streamsize>(size));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}

} // namespace translucency
