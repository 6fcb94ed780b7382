# MICA_SANITIZE="address;undefined" or "thread": instrument everything we compile.
if(MICA_SANITIZE)
  string(REPLACE ";" "," _mica_san "${MICA_SANITIZE}")
  add_compile_options(-fsanitize=${_mica_san} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${_mica_san})
endif()
