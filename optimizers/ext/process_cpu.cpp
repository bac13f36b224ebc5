#include "optimizers/ext/process_cpu.hpp"

#include <dirent.h>
#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace dsb {

namespace {

// what a run's CPU needs of one /proc/PID/stat line (proc(5) numbers its fields from 1)
struct StatCpu {
  long long pgrp = -1;
  unsigned long long ticks = 0;  // utime + stime + cutime + cstime
};

bool read_stat(const char* pid, StatCpu& out) {
  char path[64];
  std::snprintf(path, sizeof path, "/proc/%s/stat", pid);
  FILE* f = std::fopen(path, "re");
  if (!f) return false;  // it ended meanwhile
  char buf[1024];
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  buf[n] = '\0';
  // the command name may hold spaces and parentheses: the fields start after the last ')'
  const char* p = std::strrchr(buf, ')');
  if (!p) return false;
  ++p;
  // fields 3.. : state ppid pgrp session tty_nr tpgid flags minflt cminflt majflt cmajflt utime
  // stime cutime cstime (fields 14-17)
  long long field[18] = {};
  int k = 3;
  char* end = nullptr;
  while (k <= 17 && *p) {
    while (*p == ' ') ++p;
    if (k == 3) {  // state: one character
      ++p;
    } else {
      field[k] = std::strtoll(p, &end, 10);
      if (end == p) return false;
      p = end;
    }
    ++k;
  }
  if (k <= 17) return false;
  out.pgrp = field[5];
  out.ticks = static_cast<unsigned long long>(field[14] + field[15] + field[16] + field[17]);
  return true;
}

}  // namespace

double process_group_cpu_seconds(pid_t pgid) {
  DIR* proc = ::opendir("/proc");
  if (!proc) return 0.0;
  unsigned long long ticks = 0;
  while (const dirent* e = ::readdir(proc)) {
    if (!std::isdigit(static_cast<unsigned char>(e->d_name[0]))) continue;
    StatCpu s;
    if (read_stat(e->d_name, s) && s.pgrp == static_cast<long long>(pgid)) ticks += s.ticks;
  }
  ::closedir(proc);
  static const long hz = ::sysconf(_SC_CLK_TCK);
  return static_cast<double>(ticks) / static_cast<double>(hz > 0 ? hz : 100);
}

double rusage_cpu_seconds(const rusage& usage) {
  const auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec);
  };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

}  // namespace dsb
