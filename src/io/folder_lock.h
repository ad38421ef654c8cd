// An exclusive lock on a results folder for the life of the object, so that
// two estlab processes never write one folder at once (`estlab study`,
// `estlab merge`): flock(2) on FOLDER/.lock, which holds the owner's PID for
// the message the second process gets. The lock goes with the process (also
// when it is killed); the file stays, empty of meaning, and is not a result.
//
// Usage:
//   FolderLock lock(dir);   // throws InputError naming the other PID
//   ... write dir/...
//
// WARNING: flock is advisory and local: it does not protect a folder on NFS
// shared between machines (give each shard its own folder there).
#ifndef ESTLAB_IO_FOLDER_LOCK_H_
#define ESTLAB_IO_FOLDER_LOCK_H_

#include <string>

namespace estlab {

class FolderLock {
 public:
  static constexpr const char* kFileName = ".lock";

  // `folder` must exist. Throws InputError when another process holds it
  // or the lock file cannot be made.
  explicit FolderLock(const std::string& folder);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

 private:
  int fd_ = -1;
};

// True when a process holds the lock of `folder` now (probed, not taken).
bool FolderLockHeld(const std::string& folder);

// True when `folder` holds nothing but (possibly) the lock file.
bool FolderIsEmptyButLock(const std::string& folder);

}  // namespace estlab

#endif  // ESTLAB_IO_FOLDER_LOCK_H_
