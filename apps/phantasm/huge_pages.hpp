// The phantasm command's memory on transparent huge pages.
#pragma once

#include <optional>
#include <string>

namespace phantasm::cli {

/// The GLIBC_TUNABLES that add glibc.malloc.hugetlb=1 to `given` (the variable's value, null when
/// it is not set), or nothing when `given` names that tunable already.
std::optional<std::string> tunables_with_huge_pages(const char* given);

/// Starts the command again, the same process with the same arguments, with glibc's malloc
/// asking the kernel for transparent huge pages (GLIBC_TUNABLES glibc.malloc.hugetlb=1), unless
/// the environment names that tunable already (the restarted command, or a user who chose).
/// Returns when it does not restart: the tunable named, or the restart failed (the environment is
/// then as it was).
///
/// A run allocates volumes of tens of megabytes again and again (level sets, fractions, fields,
/// images), and the kernel maps each in 4 KiB pages as it is first written; Debian's kernel gives
/// huge pages (2 MiB) only to memory that asks for them (transparent_hugepage=madvise), and glibc
/// asks only when the tunable is set, which it reads at start. The values computed are the same
/// (docs/performance.md has the times). The programs the command starts inherit the setting.
void restart_with_huge_pages(char** argv);

} // namespace phantasm::cli
