// Running other programs: a word quoted for /bin/sh, and a command run
// through it with its output captured (gnuplot for figures, sbatch for
// `estlab study --slurm`).
//
// Usage:
//   std::string out;
//   if (RunShell("sbatch --parsable " + ShellQuote(script), &out) != 0) ... out says why
#ifndef ESTLAB_IO_SHELL_H_
#define ESTLAB_IO_SHELL_H_

#include <string>

namespace estlab {

// 'text' for the shell ('\'' for a quote): one word, nothing expanded.
std::string ShellQuote(const std::string& text);

// Runs `command` with /bin/sh; *output gets its stdout and stderr. Returns
// its exit status, -1 when it could not run or did not exit normally.
int RunShell(const std::string& command, std::string* output);

}  // namespace estlab

#endif  // ESTLAB_IO_SHELL_H_
