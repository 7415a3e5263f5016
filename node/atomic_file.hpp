// Replaces a small file so that a crash at any moment leaves either the old or the new
// contents: a temporary file is written, fsynced and renamed over the old one, and the
// directory is synced so the rename itself is on the disk. Stored parameters (0x1010) and
// the LSS configuration are saved this way.
#pragma once
#include <filesystem>
#include <string>

namespace stepnode::node {

// Creates the directory if needed. False (with `error` set to the reason, naming the file)
// when the file cannot be written; the old file is then untouched.
bool write_file_atomically(const std::filesystem::path& file, const std::string& contents,
                           std::string& error);

}  // namespace stepnode::node
