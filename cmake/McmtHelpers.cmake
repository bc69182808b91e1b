# Helpers shared by the component CMakeLists.

# mcmt_add_test(NAME name SOURCES a.cc ... LIBS lib ... LABELS unit|integration|process|realdata
#               [TIMEOUT seconds])
# One GoogleTest executable, registered with ctest under its name, with its labels. Tests find the
# project root through MCMT_SOURCE_DIR and the built programs through MCMT_BIN_DIR (compile definitions).
function(mcmt_add_test)
  cmake_parse_arguments(T "" "NAME;TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} mcmt_test_udpm GTest::gtest GTest::gtest_main)
  target_compile_definitions(${T_NAME} PRIVATE
    MCMT_SOURCE_DIR="${PROJECT_SOURCE_DIR}" MCMT_BIN_DIR="${MCMT_BIN_DIR}")
  set_target_properties(${T_NAME} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  add_test(NAME ${T_NAME} COMMAND ${T_NAME} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  if(NOT T_TIMEOUT)
    set(T_TIMEOUT 300)
  endif()
  if(MCMT_SANITIZE)  # instrumented programs run 2-3x slower
    math(EXPR T_TIMEOUT "${T_TIMEOUT} * 3")
  endif()
  set_tests_properties(${T_NAME} PROPERTIES LABELS "${T_LABELS}" TIMEOUT ${T_TIMEOUT})
  # Process tests start the mcmt-* programs: build them first.
  if(TARGET mcmt_programs)
    add_dependencies(${T_NAME} mcmt_programs)
  endif()
endfunction()

# mcmt_add_program(NAME mcmt-foo SOURCES main.cc LIBS ...): a process binary in build/bin.
function(mcmt_add_program)
  cmake_parse_arguments(P "" "NAME" "SOURCES;LIBS" ${ARGN})
  add_executable(${P_NAME} ${P_SOURCES})
  target_link_libraries(${P_NAME} PRIVATE ${P_LIBS})
  set_target_properties(${P_NAME} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${MCMT_BIN_DIR})
  add_dependencies(mcmt_programs ${P_NAME})
  install(TARGETS ${P_NAME} RUNTIME DESTINATION bin)
endfunction()

# mcmt_add_bench(NAME bench_foo SOURCES ... LIBS ...): a benchmark binary in build/bench.
function(mcmt_add_bench)
  cmake_parse_arguments(B "" "NAME" "SOURCES;LIBS" ${ARGN})
  add_executable(${B_NAME} ${B_SOURCES})
  target_link_libraries(${B_NAME} PRIVATE ${B_LIBS})
  target_compile_definitions(${B_NAME} PRIVATE
    MCMT_SOURCE_DIR="${PROJECT_SOURCE_DIR}" MCMT_BIN_DIR="${MCMT_BIN_DIR}")
  set_target_properties(${B_NAME} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/bench)
endfunction()
