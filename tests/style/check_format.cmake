# Runs clang-format --dry-run --Werror over the project's C++ sources (not build trees).
file(GLOB_RECURSE files
  ${SOURCE_DIR}/src/*.cpp ${SOURCE_DIR}/src/*.hpp
  ${SOURCE_DIR}/platform/*.cpp ${SOURCE_DIR}/platform/*.hpp
  ${SOURCE_DIR}/firmware_app/*.cpp ${SOURCE_DIR}/firmware_app/*.hpp
  ${SOURCE_DIR}/tools/*.cpp ${SOURCE_DIR}/tools/*.hpp
  ${SOURCE_DIR}/tests/*.cpp ${SOURCE_DIR}/tests/*.hpp)
execute_process(COMMAND ${CLANG_FORMAT} --dry-run --Werror ${files}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "clang-format differences (run scripts/format.sh):\n${err}")
endif()
list(LENGTH files n)
message(STATUS "clang-format: ${n} files clean")
