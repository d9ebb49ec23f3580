# ASan + UBSan for the whole build (project code and tests), enabled by PHANTASM_SANITIZE.
if(PHANTASM_SANITIZE)
  set(_phantasm_san -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_compile_options(${_phantasm_san})
  add_link_options(${_phantasm_san})
endif()
