#include "harness/commands/merge_command.hpp"

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "common/error.hpp"
#include "harness/commands/command.hpp"
#include "harness/store/merge.hpp"
#include "harness/store/sqlite_db.hpp"
#include "harness/store/store.hpp"

namespace dsb {

int command_merge(const std::string& into, const std::vector<std::string>& inputs) {
  check_database_path("--into", into, false);
  if (inputs.empty()) throw UsageError("merge: give the shard databases to merge after --into FILE");
  for (const auto& in : inputs) check_merge_input(in, into);
  const bool created = !std::filesystem::exists(into);
  MergeCounts n;
  try {
    std::unique_ptr<Store> store;
    try {
      store = std::make_unique<Store>(into, Provenance{});
    } catch (const StoreError& e) {
      throw UsageError(std::string("--into: ") + e.what());
    }
    n = merge_inputs(*store, inputs);
  } catch (...) {
    if (created) remove_database_files(into);  // a refused merge leaves no new file behind
    throw;
  }
  std::cerr << fmt::format(
      "harness: merged {} files into {}: {} runs added, {} identical duplicates, {} runs replaced by further "
      "copies, {} further copies kept\n",
      inputs.size(), into, n.added, n.identical, n.replaced, n.kept);
  return 0;
}

Command merge_command() {
  return {"merge", "combine shard databases by run key (conflicting runs refused)", [](CLI::App& app) {
            auto into = std::make_shared<std::string>();
            auto inputs = std::make_shared<std::vector<std::string>>();
            app.add_option("--into", *into, "the merged database (created or added to)")->required();
            app.add_option("inputs", *inputs, "shard databases to merge")->required();
            return [into, inputs] { return command_merge(*into, *inputs); };
          }};
}

}  // namespace dsb
