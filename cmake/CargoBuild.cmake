# CargoBuild.cmake: claim a shared cargo target dir, build the crate and copy the
# library into this build tree, as one step that runs under `flock` on the
# target dir (cmake/Cargo.cmake). Why all three under one lock: with several
# checkouts building at once (git worktrees, sanitizer trees, a CI clone), a
# claim by one could otherwise drop the fingerprints another's cargo is
# writing, and a checkout could link a library that another rebuilt from its
# own sources between this cargo run and this link. The copy is what the
# build tree links, so it is always built from this checkout's sources.
#
#   flock <TARGET_DIR>/.rvc-build.lock cmake -DTARGET_DIR=... -DMANIFEST_DIR=... -DPACKAGE=...
#         -DCARGO=... -DJOBS=... -DLIB_NAME=... -DCOPY_TO=... -P CargoBuild.cmake
foreach(var TARGET_DIR MANIFEST_DIR PACKAGE CARGO JOBS LIB_NAME COPY_TO)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "CargoBuild.cmake: ${var} is required")
  endif()
endforeach()
include("${CMAKE_CURRENT_LIST_DIR}/CargoClaim.cmake")
set(feature_args "")
if(FEATURES)
  set(feature_args --features "${FEATURES}")
endif()
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E env "CARGO_TARGET_DIR=${TARGET_DIR}" "CARGO_BUILD_JOBS=${JOBS}"
          "${CARGO}" build --locked --release -j ${JOBS} --manifest-path "${MANIFEST_DIR}/Cargo.toml" ${feature_args}
  WORKING_DIRECTORY "${MANIFEST_DIR}"
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cargo build of ${PACKAGE} failed (${rc})")
endif()
file(COPY_FILE "${TARGET_DIR}/release/lib${LIB_NAME}.a" "${COPY_TO}" ONLY_IF_DIFFERENT)
