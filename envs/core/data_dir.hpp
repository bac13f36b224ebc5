#pragma once
// Where the project's data files live (data/: targets, tables): the DSB_DATA_DIR environment
// variable when set, else the source tree's data/ directory this build was configured from.
#include <cstdlib>
#include <string>

namespace dsb {

inline std::string data_dir() {
  if (const char* dir = std::getenv("DSB_DATA_DIR"); dir && *dir) return dir;
  return DSB_DEFAULT_DATA_DIR;
}

}  // namespace dsb
