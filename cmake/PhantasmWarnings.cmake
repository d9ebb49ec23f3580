# Warnings for the project's own targets (never for dependencies).
function(phantasm_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wno-unused-parameter)
endfunction()

# Declares a library target phantasm_<name> with alias phantasm::<name>. Without SOURCES it is a
# header-only (INTERFACE) library of the HEADERS, e.g. a stage's result types, which its users link
# without linking the stage; PUBLIC_LIBS are then its interface and PRIVATE_LIBS are not allowed.
# Every phantasm::<target> a target's files include is linked directly (scripts/include_graph.py
# checks it): PUBLIC when a header includes it, PRIVATE when only sources do.
function(phantasm_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;HEADERS;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  if(NOT ARG_SOURCES)
    if(ARG_PRIVATE_LIBS)
      message(FATAL_ERROR "phantasm_add_library(${name}): a header-only library has no PRIVATE_LIBS")
    endif()
    add_library(phantasm_${name} INTERFACE ${ARG_HEADERS})
    add_library(phantasm::${name} ALIAS phantasm_${name})
    target_include_directories(phantasm_${name} INTERFACE $<BUILD_INTERFACE:${PHANTASM_INCLUDE_ROOT}>)
    target_link_libraries(phantasm_${name} INTERFACE ${ARG_PUBLIC_LIBS})
    return()
  endif()
  add_library(phantasm_${name} STATIC ${ARG_SOURCES} ${ARG_HEADERS})
  # Position-independent so that the Python module can link the same libraries.
  set_target_properties(phantasm_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  add_library(phantasm::${name} ALIAS phantasm_${name})
  target_include_directories(phantasm_${name} PUBLIC $<BUILD_INTERFACE:${PHANTASM_INCLUDE_ROOT}>)
  target_link_libraries(phantasm_${name} PUBLIC ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS})
  phantasm_set_warnings(phantasm_${name})
endfunction()
