# Warnings for the project's own targets (never for dependencies).
function(phantasm_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wno-unused-parameter)
endfunction()

# Declares a library target phantasm_<name> with alias phantasm::<name>.
function(phantasm_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  add_library(phantasm_${name} STATIC ${ARG_SOURCES})
  # Position-independent so that the Python module can link the same libraries.
  set_target_properties(phantasm_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  add_library(phantasm::${name} ALIAS phantasm_${name})
  target_include_directories(phantasm_${name} PUBLIC $<BUILD_INTERFACE:${PHANTASM_INCLUDE_ROOT}>)
  target_link_libraries(phantasm_${name} PUBLIC ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS})
  phantasm_set_warnings(phantasm_${name})
endfunction()
