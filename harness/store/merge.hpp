#pragma once
// What `harness merge` does to the files (harness/commands/merge_command.hpp says what it
// promises): every input checked before the output is opened, then every run of every input
// copied into the output by run key, in one transaction, copies of one key compared episode by
// episode and the further one kept.
#include <cstdint>
#include <string>
#include <vector>

#include "harness/store/store.hpp"

namespace dsb {

// UsageError naming `in` unless it is a harness database whose runs' configs rows are all there
// (missing, a folder, a FIFO, a foreign or broken file, the output itself: refused)
void check_merge_input(const std::string& in, const std::string& into);

// what merge_inputs did: runs new to the output, done copies equal to the output's, output
// copies replaced by further ones, and further copies already there
struct MergeCounts {
  std::int64_t added = 0, identical = 0, replaced = 0, kept = 0;
};

// Copies every run of the inputs into the store's database (all inputs or nothing); UsageError
// naming the run and both files when two copies of one key differ on an episode both hold.
MergeCounts merge_inputs(Store& store, const std::vector<std::string>& inputs);

// removes a database file and its -wal, -shm and -journal files (a refused merge's new output)
void remove_database_files(const std::string& path);

}  // namespace dsb
