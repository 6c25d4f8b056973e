#pragma once
// The benchmarks' --help: a benchmark asked for help prints its usage and does nothing else.

#include <cstdio>
#include <string_view>

// True, after printing `usage`, when an argument is --help or -h.
inline bool asked_for_help(int argc, char** argv, const char* usage) {
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::printf("%s\n", usage);
      return true;
    }
  }
  return false;
}
