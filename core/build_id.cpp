#include "core/build_id.hpp"

#include <cstdint>
#include <cstring>
#include <link.h>

namespace phantasm {

namespace {

struct Search {
  std::uintptr_t address = 0; ///< a code address of this object
  std::string id;
};

constexpr std::uint32_t k_note_gnu_build_id = 3; // NT_GNU_BUILD_ID

/// The build-id note among an object's PT_NOTE segments (name "GNU", type 3).
std::string build_id_note(const dl_phdr_info* info) {
  for (int h = 0; h < info->dlpi_phnum; ++h) {
    const ElfW(Phdr)& segment = info->dlpi_phdr[h];
    if (segment.p_type != PT_NOTE) continue;
    const auto* at = reinterpret_cast<const unsigned char*>(info->dlpi_addr + segment.p_vaddr);
    const unsigned char* end = at + segment.p_memsz;
    while (at + sizeof(ElfW(Nhdr)) <= end) {
      ElfW(Nhdr) note;
      std::memcpy(&note, at, sizeof note);
      const unsigned char* name = at + sizeof note;
      const unsigned char* descriptor = name + ((note.n_namesz + 3u) & ~3u);
      const unsigned char* next = descriptor + ((note.n_descsz + 3u) & ~3u);
      if (next > end) break;
      if (note.n_type == k_note_gnu_build_id && note.n_namesz == 4 && std::memcmp(name, "GNU", 4) == 0) {
        static const char* hex = "0123456789abcdef";
        std::string id;
        for (std::uint32_t b = 0; b < note.n_descsz; ++b) {
          id += hex[descriptor[b] >> 4];
          id += hex[descriptor[b] & 15];
        }
        return id;
      }
      at = next;
    }
  }
  return {};
}

int visit(dl_phdr_info* info, std::size_t, void* data) {
  auto* search = static_cast<Search*>(data);
  for (int h = 0; h < info->dlpi_phnum; ++h) {
    const ElfW(Phdr)& segment = info->dlpi_phdr[h];
    if (segment.p_type != PT_LOAD) continue;
    const std::uintptr_t begin = info->dlpi_addr + segment.p_vaddr;
    if (search->address >= begin && search->address < begin + segment.p_memsz) {
      search->id = build_id_note(info);
      return 1; // this object holds the code: stop
    }
  }
  return 0;
}

} // namespace

std::string code_build_id() {
  static const std::string id = [] {
    Search search;
    search.address = reinterpret_cast<std::uintptr_t>(&code_build_id);
    dl_iterate_phdr(visit, &search);
    return search.id;
  }();
  return id;
}

} // namespace phantasm
