# ASan + UBSan for the whole build (project code and tests), enabled by PHANTASM_SANITIZE.
# UBSan's checks are those that numerical code trips over: integer overflow, shifts, division by
# zero, array bounds, a double out of an integer's range converted to it (float-cast-overflow,
# which -fsanitize=undefined leaves out), invalid bool and enum values, a missing return,
# unreachable code, null arguments to functions that forbid them. Left out are null, alignment,
# object-size, vptr and pointer-overflow: with g++ they instrument every pointer access and more
# than double the compile time of template-heavy files (patch_fit.cpp 12 s -> 31 s), while a null
# dereference and an access outside an object still end the run under ASan (SEGV, heap- or
# stack-buffer-overflow). The fuzz targets (fuzz/CMakeLists.txt) are programs of this tree and
# run with the same checks.
# clang's "bounds" adds local-bounds, which ends the program on an illegal instruction with no
# message or stack where ASan would report the overflow with its file and line: clang gets
# array-bounds, the check g++'s "bounds" makes.
# clang's OpenMP runtime is libomp, while OpenBLAS (under CHOLMOD) needs g++'s libgomp. libomp
# defines libgomp's entry points with libgomp's symbol versions (GOMP_parallel@GOMP_4.0,
# omp_set_num_threads@OMP_1.0, ...), and every program that runs OpenMP code links libomp itself,
# so the loader finds it before libgomp, which only OpenBLAS asks for: OpenBLAS's parallel regions
# run on libomp's threads and read the thread count sim/newton.cpp sets (SingleThreadedBlas).
# libgomp is loaded but none of its functions is called (LD_DEBUG=bindings shows every omp_ and
# GOMP_ symbol of OpenBLAS, CHOLMOD and LAPACK bound to libomp).
if(PHANTASM_SANITIZE)
  set(_phantasm_bounds bounds)
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    set(_phantasm_bounds array-bounds)
  endif()
  set(_phantasm_ubsan signed-integer-overflow,shift,integer-divide-by-zero,${_phantasm_bounds},float-cast-overflow,bool,enum)
  string(APPEND _phantasm_ubsan ,return,unreachable,vla-bound,builtin,nonnull-attribute,returns-nonnull-attribute)
  set(_phantasm_san -fsanitize=address,${_phantasm_ubsan} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_compile_options(${_phantasm_san})
  add_link_options(${_phantasm_san})
  # ASan's checks as calls into its runtime instead of inline code (clang): the inline checks
  # multiply the code the backend optimizes (the scene's heaviest unit 60 s -> 42 s; the whole tree
  # 1049 s -> 834 s of processor time). A call per memory access costs run time in hot loops: the
  # solver's (sim/) keep the inline checks (phantasm_sanitizer_inline_checks, the top-level
  # CMakeLists.txt). The fast tests took 224 s of processor time so, 308 s with the solver's checks
  # outline too (the contact cantilever 51 s against 11 s), 175 s with every check inline.
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    add_compile_options(-fsanitize-address-outline-instrumentation)
  endif()
endif()

# phantasm_sanitizer_inline_checks(target...): ASan's checks compiled inline in these targets,
# whose loops the sanitizer tests run hot (see above). Nothing outside the clang sanitizer tree.
function(phantasm_sanitizer_inline_checks)
  if(PHANTASM_SANITIZE AND CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    foreach(target IN LISTS ARGN)
      target_compile_options(${target} PRIVATE -fno-sanitize-address-outline-instrumentation)
    endforeach()
  endif()
endfunction()
