# ASan + UBSan for the whole build (project code and tests), enabled by PHANTASM_SANITIZE.
if(PHANTASM_SANITIZE)
  set(_phantasm_san -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
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
