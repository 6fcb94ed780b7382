# SPDX-License-Identifier: Apache-2.0
# MICA_SANITIZE="address;undefined" or "thread": instrument everything we compile.
if(MICA_SANITIZE)
  string(REPLACE ";" "," _mica_san "${MICA_SANITIZE}")
  add_compile_options(-fsanitize=${_mica_san} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  if("undefined" IN_LIST MICA_SANITIZE)
    # UBSan's null and alignment checks on every Eigen access doubled the compile time (CI); a
    # null access still stops under ASan (SEGV with its stack), and our types are naturally aligned.
    add_compile_options(-fno-sanitize=alignment,null)
  endif()
  add_link_options(-fsanitize=${_mica_san})
endif()
