#include "src/io/shell.h"

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

int RunProgram(const std::vector<std::string>& argv, std::string* output) {
  if (argv.empty()) return 127;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  int fd[2];
  if (::pipe(fd) != 0) return -1;
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd[0]);
    ::close(fd[1]);
    return -1;
  }
  if (pid == 0) {  // the child: stdout and stderr into the pipe, then exec
    ::dup2(fd[1], 1);
    ::dup2(fd[1], 2);
    ::close(fd[0]);
    ::close(fd[1]);
    ::execvp(args[0], args.data());
    // Only async-signal-safe calls here (no allocation after fork).
    const char* parts[] = {args[0], ": cannot run it (not found on PATH, or not executable)\n"};
    for (const char* p : parts)
      if (::write(2, p, std::strlen(p)) < 0) break;
    _exit(127);
  }
  ::close(fd[1]);
  char buf[512];
  for (ssize_t n; (n = ::read(fd[0], buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    output->append(buf, size_t(n));
  }
  ::close(fd[0]);
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
