# ASan + UBSan for the whole build (project code and tests), enabled by PHANTASM_SANITIZE.
# UBSan's checks are those that numerical code trips over: integer overflow, shifts, division by
# zero, array bounds, a double out of an integer's range converted to it (float-cast-overflow,
# which -fsanitize=undefined leaves out), invalid bool and enum values, a missing return,
# unreachable code, null arguments to functions that forbid them. Left out are null, alignment,
# object-size, vptr and pointer-overflow: with g++ they instrument every pointer access and more
# than double the compile time of template-heavy files (patch_fit.cpp 12 s -> 31 s), while a null
# dereference and an access outside an object still end the run under ASan (SEGV, heap- or
# stack-buffer-overflow). The fuzz build (clang, below) keeps the whole of -fsanitize=undefined
# on the parsers and readers that take hostile input.
if(PHANTASM_SANITIZE)
  set(_phantasm_ubsan signed-integer-overflow,shift,integer-divide-by-zero,bounds,float-cast-overflow,bool,enum)
  string(APPEND _phantasm_ubsan ,return,unreachable,vla-bound,builtin,nonnull-attribute,returns-nonnull-attribute)
  set(_phantasm_san -fsanitize=address,${_phantasm_ubsan} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_compile_options(${_phantasm_san})
  add_link_options(${_phantasm_san})
endif()

# libFuzzer targets (fuzz/): every file of the build gets the fuzzer's coverage instrumentation
# and ASan + UBSan; the targets link the fuzzer's main (fuzz/CMakeLists.txt). clang only.
if(PHANTASM_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "PHANTASM_FUZZ needs clang (libFuzzer); found ${CMAKE_CXX_COMPILER_ID}")
  endif()
  set(PHANTASM_FUZZ_SANITIZERS -fsanitize=address,undefined -fno-sanitize-recover=undefined)
  add_compile_options(-fsanitize=fuzzer-no-link ${PHANTASM_FUZZ_SANITIZERS} -fno-omit-frame-pointer)
  add_link_options(${PHANTASM_FUZZ_SANITIZERS})
endif()
