#pragma once
// `harness merge --into OUT IN...`: combines shard databases by run key. A run new to OUT is
// copied with its evals (and, unfinished, its journal, so it resumes there). Copies of one run
// key in several files must agree on every episode that both hold (wall times aside; two done
// copies on everything), or the merge is refused (exit 2) with a line naming the run and both
// inputs, and nothing is written: one transaction over all inputs, and an OUT the merge created
// is removed again. Of consistent copies the one kept is done over failed over running, then the
// one with more episodes, then the one whose stored bytes sort first, so the result never
// depends on the order of the inputs. Runs of other harness versions or configs have other keys
// and stay apart. Every input is checked before OUT is opened (opened read-only: a read-only
// file or mount is fine): a harness database whose runs' configs rows are all there; an error
// names the input at fault. Returns the exit code.
#include <string>
#include <vector>

namespace dsb {

int command_merge(const std::string& into, const std::vector<std::string>& inputs);

}  // namespace dsb
