#include "fuzz/fuzz_support.hpp"

#include <unistd.h>

#include <fstream>
#include <iostream>

namespace phantasm::fuzz {
namespace {

struct ScratchFolder {
  std::filesystem::path path;
  ScratchFolder() {
    std::string pattern = (std::filesystem::temp_directory_path() / "phantasm-fuzz-XXXXXX").string();
    if (!mkdtemp(pattern.data())) {
      std::perror("phantasm fuzz: mkdtemp");
      std::abort();
    }
    path = pattern;
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

} // namespace

const std::filesystem::path& scratch_folder() {
  static const ScratchFolder folder;
  return folder.path;
}

std::filesystem::path write_scratch_file(const std::string& name, const std::uint8_t* data,
                                         std::size_t size) {
  const std::filesystem::path path = scratch_folder() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) finding("could not write the scratch file " + path.string());
  return path;
}

void unexpected_exception(const char* what_ran, const std::exception* error) {
  std::cerr << "phantasm fuzz: " << what_ran << " threw ";
  if (error)
    std::cerr << typeid(*error).name() << " (not InputError): " << error->what() << '\n';
  else
    std::cerr << "something that is not a std::exception\n";
  std::abort();
}

void finding(const std::string& message) {
  std::cerr << "phantasm fuzz: " << message << '\n';
  std::abort();
}

} // namespace phantasm::fuzz
