#include "src/io/shell.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace estlab {

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "'\\''";
    else
      out += c;
  }
  return out + "'";
}

std::string ShellJoin(const std::vector<std::string>& words) {
  std::string out;
  for (const std::string& w : words) {
    if (!out.empty()) out += ' ';
    const bool plain = !w.empty() && w.find_first_not_of(
                                         "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                         "0123456789-_=.,:/+@%") == std::string::npos;
    out += plain ? w : ShellQuote(w);
  }
  return out;
}

int RunShell(const std::string& command, std::string* output) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return -1;
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) *output += buf;
  const int status = ::pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

namespace {

// Reads both pipes to their ends (poll: a child filling one while this
// waits on the other would block both).
void DrainPipes(int out_fd, int err_fd, std::string* out, std::string* err) {
  pollfd fds[2] = {{out_fd, POLLIN, 0}, {err_fd, POLLIN, 0}};
  std::string* sinks[2] = {out, err};
  int open = 2;
  char buf[512];
  while (open > 0) {
    if (::poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || fds[i].revents == 0) continue;
      const ssize_t n = ::read(fds[i].fd, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n > 0) {
        sinks[i]->append(buf, size_t(n));
      } else {  // end (or an error): this one is done
        ::close(fds[i].fd);
        fds[i].fd = -1;
        --open;
      }
    }
  }
  for (const pollfd& f : fds)
    if (f.fd >= 0) ::close(f.fd);
}

}  // namespace

int RunProgram(const std::vector<std::string>& argv, std::string* out, std::string* err) {
  if (argv.empty()) return 127;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  int o[2], e[2];
  if (::pipe2(o, O_CLOEXEC) != 0) return 127;
  if (::pipe2(e, O_CLOEXEC) != 0) {
    ::close(o[0]);
    ::close(o[1]);
    return 127;
  }
  const pid_t pid = ::fork();
  if (pid < 0) {
    for (int fd : {o[0], o[1], e[0], e[1]}) ::close(fd);
    return 127;
  }
  if (pid == 0) {  // the child: stdout and stderr into the pipes, then exec
    // dup2 clears close-on-exec on the copies; the originals close at exec
    // (a pipe end that is already 1 or 2, the parent's being closed, keeps
    // its descriptor: clear the flag there).
    if (o[1] == 1 ? ::fcntl(1, F_SETFD, 0) < 0 : ::dup2(o[1], 1) < 0) _exit(127);
    if (e[1] == 2 ? ::fcntl(2, F_SETFD, 0) < 0 : ::dup2(e[1], 2) < 0) _exit(127);
    ::execvp(args[0], args.data());
    // Only async-signal-safe calls here (no allocation after fork).
    const char* parts[] = {args[0], ": cannot run it (not found on PATH, or not executable)\n"};
    for (const char* p : parts)
      if (::write(2, p, std::strlen(p)) < 0) break;
    _exit(127);
  }
  ::close(o[1]);
  ::close(e[1]);
  DrainPipes(o[0], e[0], out, err);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

size_t FindControlCharacter(const std::string& text) {
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7f) return i;
  }
  return std::string::npos;
}

bool SplitWords(const std::string& text, std::vector<std::string>* words, std::string* why) {
  static const std::string kShell = "'\"$`\\;&|<>()*?[]{}~#";
  std::string word;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ' ') {
      if (!word.empty()) words->push_back(word);
      word.clear();
      continue;
    }
    const auto u = static_cast<unsigned char>(c);
    if (kShell.find(c) != std::string::npos || u < 0x20 || u == 0x7f) {
      char shown[16];
      if (u < 0x20 || u == 0x7f)
        std::snprintf(shown, sizeof shown, "0x%02x", unsigned(u));
      else
        std::snprintf(shown, sizeof shown, "'%c'", c);
      *why = std::string("shell syntax ") + shown + " at character " + std::to_string(i + 1) +
             " is not supported: give plain words (e.g. --partition=short --time=1:00:00)";
      return false;
    }
    word += c;
  }
  if (!word.empty()) words->push_back(word);
  return true;
}

}  // namespace estlab
