# Shared libraries rvc loads with dlopen when a feature first needs them
# (libpq for PostgreSQL, CycloneDDS for dds: endpoints) instead of linking
# them: loading every library at start cost each `rvc` run about 20 M
# instructions of relocations. ldd does not list them, so their sonames are
# also written to <build>/runtime-libraries.txt for the Docker image.
#
# rvc_runtime_library(<target> <define> <library file>): compiles the
# library's soname into <target> as the string macro <define>.
function(rvc_runtime_library target define file)
  execute_process(COMMAND objdump -p ${file} OUTPUT_VARIABLE dump RESULT_VARIABLE rc ERROR_QUIET)
  string(REGEX MATCH "SONAME +([^\n ]+)" found "${dump}")
  if(NOT rc EQUAL 0 OR NOT CMAKE_MATCH_1)
    message(FATAL_ERROR "rvc_runtime_library: no SONAME in ${file} (is binutils' objdump installed?)")
  endif()
  target_compile_definitions(${target} PRIVATE ${define}="${CMAKE_MATCH_1}")
  set_property(GLOBAL APPEND PROPERTY RVC_RUNTIME_LIBRARIES ${CMAKE_MATCH_1})
  target_link_libraries(${target} PRIVATE ${CMAKE_DL_LIBS})
endfunction()

# Called once at the end of the top-level CMakeLists.txt.
function(rvc_write_runtime_libraries)
  get_property(names GLOBAL PROPERTY RVC_RUNTIME_LIBRARIES)
  list(JOIN names "\n" text)
  file(CONFIGURE OUTPUT ${CMAKE_BINARY_DIR}/runtime-libraries.txt CONTENT "${text}\n" @ONLY)
endfunction()
