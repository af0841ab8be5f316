# CargoClaim.cmake: run (cmake -P) before cargo builds into a target dir that
# several checkouts share (scripts/cache-env.sh keys one by Cargo.lock, so a
# CI clone, a git worktree and the main tree all compile the Zenoh crate once).
#
# Why: cargo decides whether a path package is fresh from its dep-info, which
# names the source files by absolute path. After checkout A built the crate,
# checkout B's build checks A's files, finds them unchanged and links A's
# library: B's own Rust changes would be silently left out. So the target dir
# records which checkout built the package last; when another one builds, the
# package's fingerprints are dropped and only this crate (not its dependencies)
# is compiled again from the sources of the checkout that asks.
#
#   cmake -DTARGET_DIR=... -DMANIFEST_DIR=... -DPACKAGE=rvc-zenoh -P CargoClaim.cmake
foreach(var TARGET_DIR MANIFEST_DIR PACKAGE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "CargoClaim.cmake: ${var} is required")
  endif()
endforeach()
set(owner_file "${TARGET_DIR}/rvc-owner-${PACKAGE}.txt")
set(owner "")
if(EXISTS "${owner_file}")
  file(READ "${owner_file}" owner)
endif()
if(NOT owner STREQUAL MANIFEST_DIR)
  file(GLOB stale LIST_DIRECTORIES true "${TARGET_DIR}/release/.fingerprint/${PACKAGE}-*")
  if(stale)
    message(STATUS "cargo: ${PACKAGE} was last built from ${owner}; rebuilding it from ${MANIFEST_DIR}")
    file(REMOVE_RECURSE ${stale})
  endif()
  file(MAKE_DIRECTORY "${TARGET_DIR}")
  file(WRITE "${owner_file}" "${MANIFEST_DIR}")
endif()
