// SPDX-License-Identifier: MIT
// Runs load_mesh on a file in a forked child with a time limit (and, outside sanitizer builds, an
// address-space limit), so that a loader regression that hangs, aborts, crashes or allocates
// gigabytes fails the test that meets it instead of hanging or killing the test run.
#pragma once

#include "impact/io/load_mesh.hpp"
#include "support/sanitizer.hpp"

#include <csignal>
#include <cstring>
#include <string>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace impact::test {

/// What one isolated load did.
struct IsolatedLoad {
  enum Kind { loaded, invalid_input, other_exception, crashed, timed_out } kind = crashed;
  std::string message;  // the exception's text, or a description of the crash
  int triangles = 0;    // when loaded
};

/// Loads path (as double) in a child process killed after `seconds`.
inline IsolatedLoad isolated_load(const std::string& path, unsigned seconds = 10) {
  int fds[2];
  if (::pipe(fds) != 0) return {IsolatedLoad::crashed, "pipe failed", 0};
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    ::alarm(seconds);
#if !IMPACT_TEST_SANITIZED
    const rlim_t limit = rlim_t(2) << 30;  // 2 GiB of address space: a huge allocation throws
    struct rlimit rl{limit, limit};
    ::setrlimit(RLIMIT_AS, &rl);
#endif
    char kind = 'c';
    std::string text;
    try {
      const auto m = load_mesh<double>(path);
      kind = 'l';
      text = std::to_string(m.num_triangles());
    } catch (const InvalidInput& e) {
      kind = 'i';
      text = e.what();
    } catch (const std::exception& e) {
      kind = 'o';
      text = e.what();
    }
    const std::string out = kind + text;
    const ssize_t written = ::write(fds[1], out.data(), out.size());
    ::_exit(written == static_cast<ssize_t>(out.size()) ? 0 : 3);
  }
  ::close(fds[1]);
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = ::read(fds[0], buf, sizeof buf)) > 0;) out.append(buf, static_cast<std::size_t>(n));
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  IsolatedLoad r;
  if (WIFSIGNALED(status)) {
    r.kind = WTERMSIG(status) == SIGALRM ? IsolatedLoad::timed_out : IsolatedLoad::crashed;
    r.message = std::string("child killed by signal ") + std::to_string(WTERMSIG(status)) + " (" + ::strsignal(WTERMSIG(status)) + ")";
    return r;
  }
  if (out.empty()) {
    r.message = "child exited with status " + std::to_string(WEXITSTATUS(status)) + " and no result";
    return r;
  }
  r.message = out.substr(1);
  switch (out[0]) {
    case 'l': r.kind = IsolatedLoad::loaded; r.triangles = std::stoi(r.message); break;
    case 'i': r.kind = IsolatedLoad::invalid_input; break;
    case 'o': r.kind = IsolatedLoad::other_exception; break;
    default: r.kind = IsolatedLoad::crashed;
  }
  return r;
}

}  // namespace impact::test
