#include "apps/phantasm/huge_pages.hpp"

#include <unistd.h>

#include <cstdlib>
#include <optional>
#include <string>

namespace phantasm::cli {

std::optional<std::string> tunables_with_huge_pages(const char* given) {
  const std::string before = given ? given : "";
  if (before.find("glibc.malloc.hugetlb") != std::string::npos) return std::nullopt;
  return (before.empty() ? std::string() : before + ":") + "glibc.malloc.hugetlb=1";
}

void restart_with_huge_pages(char** argv) {
  constexpr const char* variable = "GLIBC_TUNABLES";
  const char* given = std::getenv(variable);
  const std::optional<std::string> before = given ? std::optional<std::string>(given) : std::nullopt;
  const std::optional<std::string> tunables = tunables_with_huge_pages(given);
  if (!tunables || setenv(variable, tunables->c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);
  // Not restarted (no /proc, say): run on as started, and start other programs as before.
  if (before) {
    setenv(variable, before->c_str(), 1);
  } else {
    unsetenv(variable);
  }
}

} // namespace phantasm::cli
