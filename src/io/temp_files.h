// The temporary files of OutputFile (".estlab-<pid>-<n>.tmp" beside each
// output) never outlive the process that made them:
//   - RegisterTempFile / UnregisterTempFile keep a table of the live ones,
//     which the SIGINT/SIGTERM handler of InstallTempFileCleanup unlinks
//     before the signal's default action ends the process;
//   - RemoveStaleTempFiles deletes those in a folder whose process is gone
//     (a SIGKILL, a power cut), the first time a later process writes there.
//
// Usage (estlab's main):
//   InstallTempFileCleanup();
// Warning: `estlab study` replaces the handlers for its graceful stop (it
// finishes the running runs and commits or removes every output itself).
#ifndef ESTLAB_IO_TEMP_FILES_H_
#define ESTLAB_IO_TEMP_FILES_H_

#include <string>

namespace estlab {

// ".estlab-<pid>-<n>.tmp" beside `target` (in its folder): short, so that
// any name that fits the file system's 255-byte limit can be written; n
// counts up per process (thread-safe).
std::string TempPathBeside(const std::string& target);

void RegisterTempFile(const std::string& path);
void UnregisterTempFile(const std::string& path);
void InstallTempFileCleanup();

// Removes the files ".estlab-<pid>-<n>.tmp" of `folder` whose pid is not a
// running process, and the folders of that name (`estlab merge` builds its
// OUT in one); returns how many.
int RemoveStaleTempFiles(const std::string& folder);

}  // namespace estlab

#endif  // ESTLAB_IO_TEMP_FILES_H_
