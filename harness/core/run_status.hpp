#pragma once
// A run's status. The database stores three of them as text (runs.status: 'done', 'failed',
// 'running'; docs/database.md); the runner also knows two that never reach it: a run stopped by a
// signal (committed as 'running', resumed later) and a run whose journal did not fit it (started
// over without the journal, then 'done' or 'failed').
#include <optional>
#include <string>
#include <string_view>

namespace dsb {

enum class RunStatus {
  done,         // the budget is spent or the optimizer ended: the only status that counts as a result
  failed,       // the optimizer or the env raised an error; runs.error says which
  running,      // started, not ended: its committed episodes and journal let the next start resume it
  interrupted,  // runner only: stopped by a signal mid-run, stored as running
  diverged,     // runner only: a resumed run asked what its journal does not hold
};

// the text the database stores: "done", "failed" or "running" (interrupted is stored as running;
// diverged never is: the runner starts the run over)
inline std::string_view stored_text(RunStatus s) {
  switch (s) {
    case RunStatus::done: return "done";
    case RunStatus::failed: return "failed";
    case RunStatus::running:
    case RunStatus::interrupted: return "running";
    case RunStatus::diverged: break;
  }
  return "failed";
}

// the status of a database's runs.status text (nullopt for any other text)
inline std::optional<RunStatus> stored_status(std::string_view text) {
  if (text == "done") return RunStatus::done;
  if (text == "failed") return RunStatus::failed;
  if (text == "running") return RunStatus::running;
  return std::nullopt;
}

}  // namespace dsb
