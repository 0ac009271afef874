# SPDX-License-Identifier: Apache-2.0

# ido_add_module(NAME SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates library ido_<NAME> with alias ido::<NAME>, exported as ido::<NAME>.
function(ido_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(ido_${name} ${ARG_SOURCES})
  add_library(ido::${name} ALIAS ido_${name})
  set_target_properties(ido_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME ido_${name})
  target_include_directories(ido_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(ido_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  ido_set_warnings(ido_${name})
  install(TARGETS ido_${name} EXPORT idoTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()

# ido_add_test(NAME SOURCES ... LIBS ... [LABELS ...] [TIMEOUT s])
# One GoogleTest executable; every TEST in it becomes a ctest test (gtest_discover_tests).
# Label "slow" marks tests skipped in the sanitizer builds; "data" marks tests that need
# ../shared/data (they skip themselves when it is absent).
function(ido_add_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} ido_test_support GTest::gtest GTest::gmock GTest::gtest_main)
  ido_set_warnings(${name})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  set(props TIMEOUT ${ARG_TIMEOUT})
  if(ARG_LABELS)
    # One label: gtest_discover_tests hands the properties on as a flat list, so a second
    # label would be read as a property name (real_data_test's "data;slow" lost its "slow").
    list(LENGTH ARG_LABELS n_labels)
    if(n_labels GREATER 1)
      message(FATAL_ERROR "ido_add_test(${name}): give one label, not ${ARG_LABELS}")
    endif()
    list(APPEND props LABELS "${ARG_LABELS}")
  endif()
  if(IDO_SANITIZE MATCHES "address")
    # Leaks inside Mesa's OSMesa (the headless renderer) are Mesa's own, see the file.
    # intercept_tls_get_addr=0: gcc 12's runtime (as LLVM's up to 16) misreads a dynamic TLS
    # block that happens to start 16 bytes past a page as a pre-2.25 glibc header, and the leak
    # checker's tracer then dies on exit ("Tracer caught signal 11") at random; Mesa's dlopen'ed
    # drivers are where dynamic TLS lives in ido's processes.
    list(APPEND props ENVIRONMENT
      "LSAN_OPTIONS=suppressions=${PROJECT_SOURCE_DIR}/tests/sanitizer/lsan.supp:print_suppressions=0:intercept_tls_get_addr=0")
  endif()
  gtest_discover_tests(${name} PROPERTIES ${props} DISCOVERY_TIMEOUT 60)
endfunction()
