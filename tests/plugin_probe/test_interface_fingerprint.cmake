# cmake -DSCRIPT=cmake/interface_fingerprint.cmake -DWORK=<empty folder> -P test_interface_fingerprint.cmake
#
# The handshake's value (cmake/interface_fingerprint.cmake) must change with a header's content,
# a header's path and the toolchain, and with nothing else: the same inputs give the same value
# and leave the generated header untouched (so its includers do not recompile).
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}/src/core")
file(WRITE "${WORK}/src/core/a.h" "struct A { int x; };\n")
file(WRITE "${WORK}/src/core/b.h" "struct B { float y; };\n")
file(WRITE "${WORK}/list.txt" "${WORK}/src/core/b.h\n${WORK}/src/core/a.h\n")

function(fingerprint toolchain out_var)
  execute_process(COMMAND "${CMAKE_COMMAND}" "-DLIST_FILE=${WORK}/list.txt" "-DSOURCE_DIR=${WORK}/src"
                          "-DTOOLCHAIN=${toolchain}" "-DOUTPUT=${WORK}/fp.h" -P "${SCRIPT}"
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "interface_fingerprint.cmake failed (${rc})")
  endif()
  file(READ "${WORK}/fp.h" text)
  string(REGEX MATCH "LPT_INTERFACE_FINGERPRINT \"([0-9a-f]+)\"" matched "${text}")
  set(value "${CMAKE_MATCH_1}")
  string(LENGTH "${value}" digits)
  if(NOT digits EQUAL 16)
    message(FATAL_ERROR "no 16-digit fingerprint in ${WORK}/fp.h: ${text}")
  endif()
  set(${out_var} "${value}" PARENT_SCOPE)
endfunction()

function(expect_equal what a b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "${what}: ${a} != ${b}")
  endif()
endfunction()
function(expect_differ what a b)
  if(a STREQUAL b)
    message(FATAL_ERROR "${what}: both ${a}")
  endif()
endfunction()

fingerprint("GNU 12.2 c++17 flags=[] sanitize=OFF" base)
file(TIMESTAMP "${WORK}/fp.h" written "%s")
execute_process(COMMAND "${CMAKE_COMMAND}" -E sleep 1.1)
fingerprint("GNU 12.2 c++17 flags=[] sanitize=OFF" again)
expect_equal("the same inputs" "${base}" "${again}")
file(TIMESTAMP "${WORK}/fp.h" rewritten "%s")
expect_equal("the generated header's time after an unchanged hash" "${written}" "${rewritten}")

fingerprint("GNU 12.2 c++17 flags=[] sanitize=ON" sanitized)
expect_differ("a sanitized build" "${base}" "${sanitized}")
fingerprint("GNU 12.2 c++17 flags=[-D_GLIBCXX_DEBUG] sanitize=OFF" debug_stl)
expect_differ("another CMAKE_CXX_FLAGS" "${base}" "${debug_stl}")
fingerprint("Clang 14.0 c++17 flags=[] sanitize=OFF" clang)
expect_differ("another compiler" "${base}" "${clang}")

file(WRITE "${WORK}/src/core/a.h" "struct A { int x; int z; };\n")
fingerprint("GNU 12.2 c++17 flags=[] sanitize=OFF" edited)
expect_differ("an edited header" "${base}" "${edited}")
file(WRITE "${WORK}/src/core/a.h" "struct A { int x; };\n")
fingerprint("GNU 12.2 c++17 flags=[] sanitize=OFF" restored)
expect_equal("the header restored" "${base}" "${restored}")

file(MAKE_DIRECTORY "${WORK}/src/latent")
file(RENAME "${WORK}/src/core/a.h" "${WORK}/src/latent/a.h")
file(WRITE "${WORK}/list.txt" "${WORK}/src/core/b.h\n${WORK}/src/latent/a.h\n")
fingerprint("GNU 12.2 c++17 flags=[] sanitize=OFF" moved)
expect_differ("a header moved to another folder" "${base}" "${moved}")
message(STATUS "fingerprint ${base}: changes with content, path and toolchain")
