#pragma once
// `harness merge --into OUT IN...`: combines shard databases by run key (design.md "Cluster
// runs"). A run new to OUT is copied with its evals (and, unfinished, its journal, so it resumes
// there); the same finished run in two files must have the same evals (wall times aside) or the
// merge is refused with a one-line error naming the run, and nothing is written (one transaction
// over all inputs); a finished run is never replaced by an unfinished one, and of two unfinished
// copies the one with more committed episodes is kept. Runs of other harness versions or configs
// have other keys and stay apart. Every input is checked to be a harness database before OUT is
// opened. Returns the exit code.
#include <string>
#include <vector>

namespace dsb {

int command_merge(const std::string& into, const std::vector<std::string>& inputs);

}  // namespace dsb
