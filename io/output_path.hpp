// The one way output file names are joined to an output folder, so that no name taken from a
// scene, a sweep or the command line can make a path outside that folder; and the checks made
// before an existing path is replaced.
#pragma once

#include <filesystem>
#include <string_view>

namespace phantasm {

/// `folder / name` for one file or folder name made from user-given parts (organ, tissue,
/// subject names). Refused with an InputError naming the name: an empty name, ".", "..", a name
/// with '/', '\\', NUL or another control character, or an absolute path. The result is always
/// directly inside `folder`.
/// @param folder the output folder (or a folder inside it)
/// @param name a single path component
std::filesystem::path output_file(const std::filesystem::path& folder, std::string_view name);

/// Checks that `path`, lexically normalised, lies inside `root` (or is `root`): no ".." leaves
/// it. Throws an InputError naming both otherwise. Used as the last check on every file a
/// dataset writer is about to write.
void require_inside(const std::filesystem::path& root, const std::filesystem::path& path);

/// The nearest existing folder of `path` (its parent, its parent's parent, ...) that is not a
/// folder, the reason the path cannot be made ("notes.txt" of "notes.txt/out/x.json"); empty when
/// every existing one is a folder.
std::filesystem::path file_in_the_way(const std::filesystem::path& path);

/// Why a folder could not be made, after "<folder>: ": "expected <file> to be a folder (or not to
/// exist), found a file" when a file holds the place of one of its parents, else "expected a
/// folder phantasm can create, found: <the system's reason>".
std::string folder_creation_problem(const std::filesystem::path& folder, const std::error_code& error);

/// The message for a folder that could not be made because a file holds its place or a parent's
/// ("<path>: expected <file> to be a folder (or not to exist), found a file"), or "" when the
/// error is of another kind.
std::string file_in_the_way_message(const std::filesystem::filesystem_error& error);

/// Refuses (InputError) to replace an existing path that is not a regular file (a device node,
/// a folder, a FIFO, a socket): writing "to" /dev/null must not replace the node. A missing path
/// and a symbolic link to a regular file are accepted. Refuses as well a path one of whose
/// folders is a file ("notes.txt/out.json"), which could not be made, and a path that names no
/// file (empty, or ending in '/').
/// @param what names the option in the message, e.g. "--json"
void require_replaceable_file(const std::filesystem::path& path, std::string_view what);

/// The mark of a sweep batched into a dataset: a batch of another sweep into the same folder
/// while this one runs is refused, so two sweeps never mix their subjects in one dataset (shards of
/// one sweep share the folder). An empty file OUT/.phantasm-sweep-<id> held with a shared flock()
/// for the life of the object and left behind (a later batch of another sweep finds it unlocked
/// and removes it).
class SweepMark {
public:
  /// @param folder the batch's output folder (existing)
  /// @param sweep_id names the sweep (hex digits, e.g. a hash of its name and subjects)
  /// @throws InputError when a batch of another sweep holds its mark in the folder
  SweepMark(const std::filesystem::path& folder, const std::string& sweep_id);
  ~SweepMark();
  SweepMark(const SweepMark&) = delete;
  SweepMark& operator=(const SweepMark&) = delete;

  /// True for the name of a sweep mark (a dataset's own file).
  static bool is_mark_name(const std::string& file_name);

private:
  int m_fd = -1;
};

/// How an output folder is held: a run alone, or batches side by side (the shards of one sweep
/// run at once into one dataset, each writing its own subjects).
enum class FolderLockMode { exclusive, shared };

/// A lock on an output folder for the life of a run or a batch, so that two writers never mix
/// their files in one dataset. Creates the folder when missing, then takes flock() on the folder
/// itself without waiting: no lock file is made, and the lock ends with the object or the
/// process (a killed run leaves nothing stale). A run holds it exclusively; batches share it, so
/// shards run side by side but a run and a batch, or two runs, never do. On a filesystem
/// without flock() support the folder is used unlocked.
class OutputFolderLock {
public:
  /// @throws InputError when the folder cannot be made (e.g. it is a file) or another process
  ///         holds the lock in a conflicting mode ("... being written by another phantasm process")
  explicit OutputFolderLock(const std::filesystem::path& folder,
                            FolderLockMode mode = FolderLockMode::exclusive);
  ~OutputFolderLock();
  OutputFolderLock(const OutputFolderLock&) = delete;
  OutputFolderLock& operator=(const OutputFolderLock&) = delete;

private:
  int m_fd = -1;
};

} // namespace phantasm
