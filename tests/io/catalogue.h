// SPDX-License-Identifier: Apache-2.0
// The bad-input catalogue (tests/data/bad/catalogue.txt), shared by the library and CLI tests.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace ido::test {

struct BadFile {
  std::string file;       ///< name inside tests/data/bad
  std::string exception;  ///< "IoError" or "InvalidInput"
  std::string location;   ///< "line N", "byte N" or "-"
  std::string fragment;   ///< must appear in the message
};

inline std::string trim(std::string s) {
  const auto b = s.find_first_not_of(" \t");
  const auto e = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

inline std::vector<BadFile> bad_catalogue() {
  std::ifstream in(fixtures_dir() / "bad" / "catalogue.txt");
  std::vector<BadFile> out;
  std::string line;
  while (std::getline(in, line)) {
    if (trim(line).empty() || trim(line)[0] == '#') continue;
    std::vector<std::string> parts;
    std::stringstream ss(line);
    std::string part;
    while (std::getline(ss, part, '|')) parts.push_back(trim(part));
    if (parts.size() == 4) out.push_back({parts[0], parts[1], parts[2], parts[3]});
  }
  return out;
}

/// How the location shows in a message: "file:N:" for lines, "file: byte N:" for offsets.
inline std::string location_text(const std::string& file, const std::string& location) {
  if (location.rfind("line ", 0) == 0) return file + ":" + location.substr(5) + ":";
  if (location.rfind("byte ", 0) == 0) return file + ": " + location + ":";
  return file;
}

}  // namespace ido::test
