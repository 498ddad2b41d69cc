# cmake -DBENCH=... -DFILE=... -DCODE=0|2 -DEXPECT=... -P expect_knot.cmake
# CODE 0: stdout must be exactly EXPECT and a newline. CODE 2: stderr must be one line
# containing EXPECT, stdout empty.
execute_process(COMMAND ${BENCH} knot ${FILE} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                ERROR_VARIABLE err)
if(NOT rc EQUAL CODE)
  message(FATAL_ERROR "exit ${rc}, expected ${CODE}; stdout '${out}' stderr '${err}'")
endif()
if(CODE EQUAL 0)
  if(NOT out STREQUAL "${EXPECT}\n")
    message(FATAL_ERROR "stdout '${out}', expected '${EXPECT}'")
  endif()
else()
  string(FIND "${err}" "${EXPECT}" at)
  string(REGEX MATCHALL "\n" newlines "${err}")
  list(LENGTH newlines lines)
  if(at LESS 0 OR NOT lines EQUAL 1 OR NOT out STREQUAL "")
    message(FATAL_ERROR "stderr '${err}' (${lines} lines), expected one line with '${EXPECT}'")
  endif()
endif()
