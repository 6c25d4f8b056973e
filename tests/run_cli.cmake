# Runs COMMAND with the |-separated ARGS in WORKDIR and checks its exit status against STATUS
# and, unless EXPECTED is "-", its standard output and standard error (concatenated) against the
# file EXPECTED.
string(REPLACE "|" ";" ARGS "${ARGS}")
execute_process(
  COMMAND ${COMMAND} ${ARGS}
  WORKING_DIRECTORY ${WORKDIR}
  RESULT_VARIABLE status
  OUTPUT_VARIABLE out
  ERROR_VARIABLE err)
if(NOT status EQUAL STATUS)
  message(FATAL_ERROR "exit status ${status}, expected ${STATUS}\nstdout:\n${out}\nstderr:\n${err}")
endif()
if(NOT EXPECTED STREQUAL "-")
  file(READ ${EXPECTED} want)
  set(got "${out}${err}")
  if(NOT got STREQUAL want)
    file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/got.txt "${got}")
    message(FATAL_ERROR "output differs from ${EXPECTED}\n--- got:\n${got}\n--- expected:\n${want}")
  endif()
endif()
