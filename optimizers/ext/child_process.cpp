#include "optimizers/ext/child_process.hpp"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <ctime>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

#include "optimizers/ext/descendant_mark.hpp"
#include "optimizers/ext/process_cpu.hpp"

extern char** environ;

namespace dsb {
namespace {

void close_fd(int& fd) {
  if (fd >= 0) ::close(fd);
  fd = -1;
}

int ms_until(ChildProcess::Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - ChildProcess::Clock::now());
  return static_cast<int>(std::clamp<std::int64_t>(left.count() + 1, 0, 60'000));
}

std::runtime_error sys_error(const std::string& what, int err) {
  return std::runtime_error(what + ": " + std::strerror(err));
}

// the process groups of the live children, for terminate_all() (a signal handler: lock-free
// atomics only). A slot is emptied before its child is reaped, so a group id in the table is
// never one the kernel has given to another process.
constexpr int kMaxChildren = 4096;
std::atomic<pid_t> g_groups[kMaxChildren];
// CLOCK_MONOTONIC nanoseconds of the first terminate_all(), 0 while none came
std::atomic<std::int64_t> g_stop_ns{0};
static_assert(std::atomic<pid_t>::is_always_lock_free && std::atomic<std::int64_t>::is_always_lock_free,
              "terminate_all() runs in a signal handler");

// a poll never sleeps longer than this, so a stop is seen within it
constexpr int kPollSliceMs = 100;

std::int64_t monotonic_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

int register_group(pid_t group) {
  for (int i = 0; i < kMaxChildren; ++i) {
    pid_t empty = 0;
    if (g_groups[i].compare_exchange_strong(empty, group)) return i;
  }
  return -1;  // a full table: this child gets no TERM from a stop, only the kill after the grace
}

void unregister_group(int& slot) {
  if (slot >= 0) g_groups[slot].store(0);
  slot = -1;
}

// The watchdog's whole life, in a process forked from a threaded one: async-signal-safe calls
// only. It ignores the signals a terminal or `kill` sends the harness's group, keeps no
// descriptor of the harness's but the pipe's read end, and waits: a byte disarms it, end of file
// (the harness is gone) kills the child's group.
[[noreturn]] void watchdog_main(int read_end, pid_t group, const char* mark) {
  struct sigaction ignore {};
  ignore.sa_handler = SIG_IGN;
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE}) ::sigaction(sig, &ignore, nullptr);
  const int guard = ::fcntl(read_end, F_DUPFD, 100);
  const int nul = ::open("/dev/null", O_RDWR);
  if (nul >= 0)
    for (int fd = 0; fd < 3; ++fd) ::dup2(nul, fd);
  ::dup2(guard >= 0 ? guard : read_end, 3);
  if (::close_range(4, ~0U, 0) != 0)
    for (int fd = 4; fd < 4096; ++fd) ::close(fd);
  char byte = 0;
  for (;;) {
    const ssize_t n = ::read(3, &byte, 1);
    if (n < 0 && errno == EINTR) continue;
    if (n == 0) {
      ::kill(-group, SIGKILL);
      kill_marked_processes(mark);  // and the descendants that left the group
    }
    ::_exit(0);
  }
}

}  // namespace

void ChildProcess::terminate_all() {
  std::int64_t none = 0;
  g_stop_ns.compare_exchange_strong(none, monotonic_ns());
  for (auto& group : g_groups) {
    const pid_t g = group.load();
    if (g > 0) ::kill(-g, SIGTERM);
  }
}

void ChildProcess::start_watchdog() {
  int guard[2];
  if (::pipe2(guard, O_CLOEXEC) != 0) return;  // no watchdog: only a killed harness would orphan the child
  const pid_t group = pid_;
  const pid_t w = ::fork();
  if (w == 0) watchdog_main(guard[0], group, mark_.c_str());
  ::close(guard[0]);
  if (w < 0) {
    ::close(guard[1]);
    return;
  }
  guard_fd_ = guard[1];
  watchdog_pid_ = w;
}

void ChildProcess::stop_watchdog() {
  if (guard_fd_ >= 0) {
    const char disarm = 'x';
    [[maybe_unused]] const ssize_t n = ::write(guard_fd_, &disarm, 1);
    close_fd(guard_fd_);
  }
  if (watchdog_pid_ > 0) {
    int status = 0;
    while (::waitpid(watchdog_pid_, &status, 0) < 0 && errno == EINTR) {}
  }
  watchdog_pid_ = -1;
}

void ChildProcess::end_if_stopped() {
  const std::int64_t since = g_stop_ns.load();
  if (since == 0 || monotonic_ns() - since < std::int64_t{kStopGraceS} * 1'000'000'000) return;
  kill();
  close_fd(in_);
  close_fd(out_fd_);
  close_fd(err_fd_);
}

ChildProcess::ChildProcess(const std::string& command) {
  // stdin: a socket pair, so that writing to a child that has gone gives EPIPE, never SIGPIPE
  // (send with MSG_NOSIGNAL); stdout, stderr: pipes. All close-on-exec on our side.
  int in_pair[2], out_pipe[2], err_pipe[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, in_pair) != 0) throw sys_error("socketpair", errno);
  if (::pipe2(out_pipe, O_CLOEXEC) != 0) {
    const int e = errno;
    ::close(in_pair[0]);
    ::close(in_pair[1]);
    throw sys_error("pipe", e);
  }
  if (::pipe2(err_pipe, O_CLOEXEC) != 0) {
    const int e = errno;
    for (int fd : {in_pair[0], in_pair[1], out_pipe[0], out_pipe[1]}) ::close(fd);
    throw sys_error("pipe", e);
  }
  // the child's side of stdin reads only
  ::shutdown(in_pair[1], SHUT_WR);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, in_pair[1], 0);
  posix_spawn_file_actions_adddup2(&actions, out_pipe[1], 1);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], 2);
  posix_spawn_file_actions_addclosefrom_np(&actions, 3);  // nothing else of ours (db, lock)
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  for (int sig : {SIGPIPE, SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGCHLD}) sigaddset(&defaults, sig);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setpgroup(&attr, 0);  // its own process group
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  // our environment plus the mark its descendants inherit (descendant_mark.hpp)
  mark_ = new_descendant_mark();
  std::vector<char*> envp;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "DSB_EXT_RUN=", 12) != 0) envp.push_back(*e);  // not a parent harness's mark
  envp.push_back(mark_.data());
  envp.push_back(nullptr);
  const int rc = ::posix_spawn(&pid_, "/bin/sh", &actions, &attr, const_cast<char* const*>(argv), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(in_pair[1]);
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  in_ = in_pair[0];
  out_fd_ = out_pipe[0];
  err_fd_ = err_pipe[0];
  if (rc != 0) {
    pid_ = -1;
    close_fd(in_);
    close_fd(out_fd_);
    close_fd(err_fd_);
    throw sys_error("posix_spawn /bin/sh", rc);
  }
  for (int fd : {in_, out_fd_, err_fd_}) ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  slot_ = register_group(pid_);
  if (g_stop_ns.load() != 0) ::kill(-pid_, SIGTERM);  // started after a stop: told at once
  start_watchdog();
}

ChildProcess::~ChildProcess() {
  kill();
  close_fd(in_);
  close_fd(out_fd_);
  close_fd(err_fd_);
}

void ChildProcess::read_available(int& fd, bool is_stdout) {
  char buf[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) {
      if (is_stdout) {
        out_.append(buf, static_cast<std::size_t>(n));
      } else {
        err_.append(buf, static_cast<std::size_t>(n));
        if (err_.size() > 2 * kStderrKeep) err_.erase(0, err_.size() - kStderrKeep);
      }
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return;
    close_fd(fd);  // end of file (or an error: the same for us)
    return;
  }
}

bool ChildProcess::pump(Clock::time_point deadline, bool want_write) {
  end_if_stopped();
  pollfd fds[3];
  int n = 0, i_out = -1, i_err = -1, i_in = -1;
  if (out_fd_ >= 0) fds[i_out = n++] = {out_fd_, POLLIN, 0};
  if (err_fd_ >= 0) fds[i_err = n++] = {err_fd_, POLLIN, 0};
  if (want_write && in_ >= 0) fds[i_in = n++] = {in_, POLLOUT, 0};
  if (n == 0) {
    // nothing left to watch: wait out the deadline in small steps is pointless; report it
    return Clock::now() < deadline;
  }
  const int rc = ::poll(fds, static_cast<nfds_t>(n), std::min(ms_until(deadline), kPollSliceMs));
  if (rc < 0 && errno != EINTR) throw sys_error("poll", errno);
  if (rc <= 0) return Clock::now() < deadline;
  if (i_out >= 0 && fds[i_out].revents) read_available(out_fd_, true);
  if (i_err >= 0 && fds[i_err].revents) read_available(err_fd_, false);
  if (i_in >= 0 && fds[i_in].revents) {
    while (!pending_.empty()) {
      const ssize_t w = ::send(in_, pending_.data(), pending_.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      if (w > 0) {
        pending_.remove_prefix(static_cast<std::size_t>(w));
        continue;
      }
      if (w < 0 && errno == EINTR) continue;
      if (w < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
      close_fd(in_);  // EPIPE, ECONNRESET: the child does not read any more
      break;
    }
  }
  return true;
}

ChildProcess::Io ChildProcess::write(std::string_view text, Clock::time_point deadline) {
  pending_ = text;
  while (!pending_.empty()) {
    if (in_ < 0) {
      pending_ = {};
      return Io::closed;
    }
    if (!pump(deadline, true) || Clock::now() >= deadline) {
      if (pending_.empty()) break;
      pending_ = {};
      return Io::timeout;
    }
  }
  return Io::ok;
}

ChildProcess::Io ChildProcess::read_line(std::string& line, Clock::time_point deadline) {
  for (;;) {
    const auto nl = out_.find('\n', scanned_);
    if (nl != std::string::npos) {
      line.assign(out_, 0, nl);
      out_.erase(0, nl + 1);
      scanned_ = 0;
      return Io::ok;
    }
    scanned_ = out_.size();
    if (out_.size() > kMaxLine) {
      too_long_ = true;
      return Io::closed;
    }
    if (out_fd_ < 0) return Io::closed;
    if (!pump(deadline, false)) return Io::timeout;
  }
}

void ChildProcess::close_stdin() { close_fd(in_); }

std::optional<int> ChildProcess::wait_exit(Clock::time_point deadline) {
  if (reaped_) return status_;
  if (pid_ < 0) return std::nullopt;
  for (;;) {
    if (reaped_) return status_;  // killed after a stop's grace (pump)
    // has it exited? (not reaped yet: its group id leaves the stop table first)
    siginfo_t info{};
    const int r = ::waitid(P_PID, static_cast<id_t>(pid_), &info, WEXITED | WNOHANG | WNOWAIT);
    if (r == 0 && info.si_pid == pid_) {
      unregister_group(slot_);
      reap();
      return status_;
    }
    if (r < 0 && errno != EINTR) return std::nullopt;
    if (Clock::now() >= deadline) return std::nullopt;
    // keep draining its output (a child blocked on a full pipe never exits), at most 10 ms a round
    pump(std::min(deadline, Clock::now() + std::chrono::milliseconds(10)), false);
    if (out_fd_ < 0 && err_fd_ < 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void ChildProcess::kill() {
  if (pid_ >= 0 && !reaped_) {
    unregister_group(slot_);
    ::kill(-pid_, SIGKILL);  // the group: the shell and what it started
    ::kill(pid_, SIGKILL);
    reap();
  }
  // whatever it started that left its group (setsid, a daemon) ends with it too
  if (!mark_.empty()) kill_marked_processes(mark_.c_str());
  stop_watchdog();
}

void ChildProcess::reap() {
  int status = 0;
  rusage usage{};
  while (::wait4(pid_, &status, 0, &usage) < 0 && errno == EINTR) {}
  reaped_ = true;
  status_ = status;
  cpu_s_ = std::max(cpu_s_, rusage_cpu_seconds(usage));
}

double ChildProcess::cpu_seconds() const {
  if (pid_ >= 0 && !reaped_) cpu_s_ = std::max(cpu_s_, process_group_cpu_seconds(pid_));
  return cpu_s_;
}

std::string ChildProcess::stderr_tail(std::size_t max_chars) const {
  std::string t = err_;
  while (!t.empty() && (t.back() == '\n' || t.back() == '\r' || t.back() == ' ')) t.pop_back();
  if (t.size() > max_chars) t = "..." + t.substr(t.size() - max_chars);
  std::string one;
  for (char c : t) {
    if (c == '\n') {
      one += " | ";
    } else if (c == '\r' || c == '\t') {
      one += ' ';
    } else {
      one += c;
    }
  }
  return one;
}

std::string describe_exit(int status) {
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status))
    return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" + ::strsignal(WTERMSIG(status)) + ")";
  return "ended with wait status " + std::to_string(status);
}

}  // namespace dsb
