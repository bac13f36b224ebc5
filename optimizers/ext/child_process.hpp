#pragma once
// A child process spoken to in lines: `/bin/sh -c COMMAND` with its stdin, stdout and stderr
// connected to us, in its own process group (a terminal's Ctrl-C reaches the harness, which
// stops the runs in order, not the child), inheriting no other descriptor of ours (the
// database's lock stays ours). Every wait has a deadline; stderr is drained all the time into a
// capped tail, shown in errors. The destructor kills (SIGKILL to the group) and reaps.
//
// The child never outlives the harness:
// - a stop (terminate_all(), from the harness's SIGTERM/SIGINT/SIGHUP handler) sends TERM to
//   every child's group at once, and every wait ends within kStopGraceS after it: a child still
//   there is killed (SIGKILL to its group) and its reads and writes end as `closed`;
// - a harness that dies without a word (SIGKILL, a crash) leaves no orphan: each child has a
//   watchdog, a small forked process that holds the read end of a pipe whose write end only the
//   harness has. The harness's death closes it; the watchdog reads end of file and kills the
//   child's group. A child that ends normally disarms it with one byte first;
// - descendants that left the child's group (setsid, a double fork) are found by the mark in
//   their environment (descendant_mark.hpp) and killed when the child is killed or reaped, and
//   by the watchdog when the harness dies.
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace dsb {

class ChildProcess {
 public:
  using Clock = std::chrono::steady_clock;

  // throws std::runtime_error when the process cannot be started
  explicit ChildProcess(const std::string& command);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  enum class Io { ok, closed, timeout };

  // writes text whole before the deadline (reading stdout and stderr meanwhile, so a child
  // that writes while we write cannot block us); closed when the child no longer reads
  Io write(std::string_view text, Clock::time_point deadline);
  // the next line of stdout without its '\n'; closed at end of file (a last unterminated line is
  // kept in partial()), timeout at the deadline. Lines over max_line bytes end the read as
  // closed with too_long() set.
  Io read_line(std::string& line, Clock::time_point deadline);
  // no more input for the child (it reads end of file)
  void close_stdin();
  // the exit status (as waitpid's) once the child has exited, before the deadline, else nullopt
  std::optional<int> wait_exit(Clock::time_point deadline);
  // SIGKILL to the group, then reap; safe to call twice
  void kill();
  // the CPU seconds the program has spent so far, its descendants in its group included
  // (process_cpu.hpp): its group's live processes read from /proc while it runs, wait4's rusage
  // once reaped; never less than an earlier reading
  double cpu_seconds() const;

  // Async-signal-safe, for a signal handler: TERM to every live child's process group now, and
  // from then on every wait of every ChildProcess ends by kStopGraceS after this call, killing
  // the child if it is still there. Children started later get TERM at once.
  static void terminate_all();
  static constexpr int kStopGraceS = 3;

  pid_t pid() const { return pid_; }
  pid_t watchdog_pid() const { return watchdog_pid_; }
  bool too_long() const { return too_long_; }
  const std::string& partial() const { return out_; }
  // the last bytes of stderr, one line (newlines shown as " | "), at most max_chars
  std::string stderr_tail(std::size_t max_chars = 400) const;

  static constexpr std::size_t kMaxLine = 256u << 20;    // 256 MiB: a 400-D batch of 10^4 gradients fits
  static constexpr std::size_t kStderrKeep = 16u << 10;  // bytes of stderr kept

 private:
  // one poll round until the deadline: reads what stdout and stderr have, writes pending input
  // when want_write; false at the deadline
  bool pump(Clock::time_point deadline, bool want_write);
  void read_available(int& fd, bool is_stdout);

  // the watchdog (see above): forked after the child, disarmed by one byte on guard_fd_
  void start_watchdog();
  void stop_watchdog();
  // after a stop's grace: the child is killed and every descriptor closed
  void end_if_stopped();
  // waits for the exited or killed child (wait4): its status and CPU
  void reap();

  pid_t pid_ = -1;
  pid_t watchdog_pid_ = -1;
  std::string mark_;   // the environment entry its descendants inherit (descendant_mark.hpp)
  int guard_fd_ = -1;  // our end of the watchdog's pipe
  int slot_ = -1;      // our entry in the table terminate_all() walks
  bool reaped_ = false;
  int status_ = 0;
  mutable double cpu_s_ = 0.0;               // the largest CPU reading so far (cpu_seconds)
  int in_ = -1, out_fd_ = -1, err_fd_ = -1;  // our ends (in_ a socket: writes never raise SIGPIPE)
  std::string out_;                          // stdout read but not yet returned as lines
  std::size_t scanned_ = 0;                  // out_[0, scanned_) holds no '\n'
  std::string err_;                          // the stderr tail
  std::string_view pending_;                 // input still to write
  bool too_long_ = false;
};

// "exited with status 3", "killed by signal 9 (Killed)"
std::string describe_exit(int wait_status);

}  // namespace dsb
