# Cargo.cmake: build a Rust staticlib with cargo as part of the CMake build.
#
#   rvc_cargo_staticlib(<target>
#     MANIFEST_DIR <dir with Cargo.toml and Cargo.lock>
#     LIB_NAME     <[lib] name in Cargo.toml, e.g. rvc_zenoh>
#     [FEATURES    <cargo features, comma-separated, e.g. shm>])
#
# Defines <target>, an INTERFACE library that links the resulting
# lib<LIB_NAME>.a plus the system libraries a Rust std staticlib needs on
# Linux (what `rustc --print native-static-libs` lists), and orders the cargo
# build before anything that links it.
#
# Always --release (the crate is a dependency, not something we debug) and
# --locked (Cargo.lock is committed: builds are reproducible and never
# silently resolve new versions). CARGO_TARGET_DIR lives in the build tree so
# compiled dependencies survive between builds of the same tree; cargo's
# parallelism follows RVC_CARGO_JOBS (default 2, the size of our machines).
#
# A shared target dir is claimed by the checkout that builds (CargoClaim.cmake)
# and the library copied into the build tree, under one lock (CargoBuild.cmake),
# so one checkout never links a library cargo built from another's sources.
#
# Ninja reruns cargo only when a file under src/, Cargo.toml or Cargo.lock
# changes (the stamp below); cargo then does its own fine-grained check.

include_guard(GLOBAL)

set(RVC_CARGO_JOBS 2 CACHE STRING "Parallel jobs for cargo builds")
# Several build trees (release, sanitizers, git worktrees) can share one cargo
# target dir so the Zenoh crate compiles once; cargo locks it while it builds.
set(RVC_CARGO_TARGET_DIR "$ENV{RVC_CARGO_TARGET_DIR}" CACHE PATH
    "cargo target dir (default: <build tree>/cargo-target)")

# A folder with lib<LIB_NAME>.a already built from the same rust/ sources (the
# image build reuses the host's, deploy/docker/build.sh --zenoh-lib): no cargo run.
set(RVC_PREBUILT_RUST_LIBS "" CACHE PATH "Folder of prebuilt Rust staticlibs (skips cargo)")

find_program(CARGO_EXECUTABLE cargo
  HINTS "$ENV{CARGO_HOME}/bin" "$ENV{HOME}/.cargo/bin"
  DOC "cargo, to build the Rust parts of rvc")

function(rvc_cargo_staticlib target)
  cmake_parse_arguments(ARG "" "MANIFEST_DIR;LIB_NAME;FEATURES" "" ${ARGN})
  if(NOT ARG_MANIFEST_DIR OR NOT ARG_LIB_NAME)
    message(FATAL_ERROR "rvc_cargo_staticlib(${target}): MANIFEST_DIR and LIB_NAME are required")
  endif()
  if(RVC_PREBUILT_RUST_LIBS)
    set(lib "${RVC_PREBUILT_RUST_LIBS}/lib${ARG_LIB_NAME}.a")
    if(NOT EXISTS "${lib}")
      message(FATAL_ERROR "RVC_PREBUILT_RUST_LIBS: ${lib} does not exist")
    endif()
    message(STATUS "${target}: prebuilt ${lib} (no cargo build)")
    add_custom_target(${target}_cargo)  # nothing to build; others may depend on it
    add_library(${target} INTERFACE)
    find_package(Threads REQUIRED)
    target_link_libraries(${target} INTERFACE
      "${lib}" Threads::Threads ${CMAKE_DL_LIBS} m rt util gcc_s)
    return()
  endif()
  if(NOT CARGO_EXECUTABLE)
    message(FATAL_ERROR
      "cargo not found: install a Rust toolchain (rustup or Debian's cargo), "
      "or configure with -DRVC_WITH_ZENOH=OFF")
  endif()

  get_filename_component(manifest_dir "${ARG_MANIFEST_DIR}" ABSOLUTE)
  set(target_dir "${RVC_CARGO_TARGET_DIR}")
  if(NOT target_dir)
    set(target_dir "${CMAKE_BINARY_DIR}/cargo-target")
  endif()
  if(ARG_FEATURES)  # its own target dir: the default build's library is never overwritten by this one
    string(REPLACE "," "-" suffix "${ARG_FEATURES}")
    set(target_dir "${target_dir}-${suffix}")
  endif()
  # The build tree links its own copy (CargoBuild.cmake says why).
  set(lib "${CMAKE_CURRENT_BINARY_DIR}/lib${ARG_LIB_NAME}.a")
  set(stamp "${CMAKE_CURRENT_BINARY_DIR}/${target}.cargo-stamp")

  # The [package] name, for CargoClaim.cmake (the first `name =` line).
  file(STRINGS "${manifest_dir}/Cargo.toml" name_line REGEX "^name *= *\"" LIMIT_COUNT 1)
  string(REGEX REPLACE "^name *= *\"([^\"]+)\".*" "\\1" package "${name_line}")

  file(GLOB_RECURSE sources CONFIGURE_DEPENDS
    "${manifest_dir}/src/*.rs" "${manifest_dir}/build.rs")

  find_program(FLOCK_EXECUTABLE flock REQUIRED DOC "flock (util-linux): one cargo build per shared target dir at a time")
  file(MAKE_DIRECTORY "${target_dir}")
  add_custom_command(
    OUTPUT "${stamp}"
    BYPRODUCTS "${lib}"
    COMMAND "${FLOCK_EXECUTABLE}" "${target_dir}/.rvc-build.lock"
            "${CMAKE_COMMAND}" "-DTARGET_DIR=${target_dir}" "-DMANIFEST_DIR=${manifest_dir}"
            "-DPACKAGE=${package}" "-DCARGO=${CARGO_EXECUTABLE}" "-DJOBS=${RVC_CARGO_JOBS}"
            "-DLIB_NAME=${ARG_LIB_NAME}" "-DCOPY_TO=${lib}" "-DFEATURES=${ARG_FEATURES}" -P "${PROJECT_SOURCE_DIR}/cmake/CargoBuild.cmake"
    COMMAND "${CMAKE_COMMAND}" -E touch "${stamp}"
    DEPENDS ${sources} "${manifest_dir}/Cargo.toml" "${manifest_dir}/Cargo.lock"
            "${PROJECT_SOURCE_DIR}/cmake/CargoBuild.cmake" "${PROJECT_SOURCE_DIR}/cmake/CargoClaim.cmake"
    WORKING_DIRECTORY "${manifest_dir}"
    COMMENT "cargo build --release ${ARG_LIB_NAME}"
    VERBATIM)
  add_custom_target(${target}_cargo DEPENDS "${stamp}")

  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_cargo)
  find_package(Threads REQUIRED)
  target_link_libraries(${target} INTERFACE
    "${lib}" Threads::Threads ${CMAKE_DL_LIBS} m rt util gcc_s)
endfunction()
