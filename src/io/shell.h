// Running other programs: a word quoted for /bin/sh, a command run through
// it with its output captured (gnuplot for figures), and a program run from
// its words without a shell (sbatch for `estlab study --slurm`, whose
// options come from the user and must never be shell code).
//
// Usage:
//   std::string out;
//   std::string err;
//   if (RunProgram({"sbatch", "--parsable", script}, &out, &err) != 0) ... err says why
//   std::vector<std::string> words;
//   if (!SplitWords(user_text, &words, &why)) ... why names the character
#ifndef ESTLAB_IO_SHELL_H_
#define ESTLAB_IO_SHELL_H_

#include <string>
#include <vector>

namespace estlab {

// 'text' for the shell ('\'' for a quote): one word, nothing expanded.
std::string ShellQuote(const std::string& text);

// The words as one shell command line, each quoted where it needs it (for
// showing a command a user may paste).
std::string ShellJoin(const std::vector<std::string>& words);

// Runs `command` with /bin/sh; *output gets its stdout and stderr. Returns
// its exit status, -1 when it could not run or did not exit normally.
int RunShell(const std::string& command, std::string* output);

// Runs argv[0] (found on PATH) with the arguments argv[1..], no shell in
// between; *out gets its stdout, *err its stderr. Returns its exit status,
// 127 when it could not be started, -1 when it did not exit normally.
int RunProgram(const std::vector<std::string>& argv, std::string* out, std::string* err);

// Splits `text` at blanks into *words. Refuses (false, *why naming the
// character and its position) quotes, '$', '`', '\', ';', '&', '|', '<',
// '>', '(', ')', '*', '?', '[', ']', '{', '}', '~', '#' and control
// characters: text a shell would read differently than word by word.
bool SplitWords(const std::string& text, std::vector<std::string>* words, std::string* why);

// The position of the first control character (< 0x20 or 0x7f: newline,
// tab, ...) in `text`, or std::string::npos.
size_t FindControlCharacter(const std::string& text);

}  // namespace estlab

#endif  // ESTLAB_IO_SHELL_H_
