# FMI fuzz tests (tests/fuzz/): both FMUs (csfh and the comb-drive actuator) compiled once more,
# glue + model + core, with AddressSanitizer + UndefinedBehaviorSanitizer (+ LeakSanitizer, part
# of ASan on Linux), each linked into its own executable with our random FMI call-sequence
# driver (tests/fuzz/fuzz_fmi.c), and with the FMU-state regression test (tests/fuzz/fmu_states.c).
# Registered with ctest (label "fuzz"). The failed-allocation test (tests/fuzz/alloc_fail.c,
# label "alloc") is built the same way, for both FMUs and both FMI versions. Included from
# CMakeLists.txt when CSFH_FUZZ is ON; needs the FMU's prerequisites (CSFH_BUILD_FMU: FMI
# headers, SUNDIALS).
#
#   cmake -S . -B build-fuzz -G Ninja -DCSFH_FUZZ=ON && cmake --build build-fuzz --target csfh_fuzz
#   ctest --test-dir build-fuzz -L fuzz --output-on-failure
#   ctest --test-dir build-fuzz -L alloc --output-on-failure
#   build-fuzz/fuzz_fmi_csfh --seeds 1 100 --sequences 50     # more seeds by hand
#   CSFH_ALLOC_FAIL=120 build-fuzz/alloc_fail_csfh_fmi2        # one failed allocation
#
# CVODE is linked through the one variable CSFH_FUZZ_CVODE (a target or library list), so that a
# different SUNDIALS build is one line away. It is not instrumented: the sanitizers watch our
# code and every allocation (ASan intercepts malloc), not CVODE's internals.
if(NOT CSFH_BUILD_FMU)
  message(FATAL_ERROR "CSFH_FUZZ needs CSFH_BUILD_FMU=ON (FMI headers and SUNDIALS)")
endif()
set(CSFH_FUZZ_CVODE csfh_sundials CACHE STRING
    "CVODE for the fuzz executables (target or libraries)")
set(CSFH_FUZZ_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=all
                    -fno-omit-frame-pointer -O1 -g)

enable_testing()

# csfh: the FMU's own sources (the FMU layer, the csfh model adapter and the physics); the
# comb-drive actuator: the same FMU layer with its own model and table
set(_fuzz_sources_csfh ${CSFH_FMU_SOURCES})
set(_fuzz_sources_combdrive ${COMBDRIVE_FMU_SOURCES})
set(_fuzz_include_csfh ${CSFH_FMU_INCLUDE_DIRS})
set(_fuzz_include_combdrive ${COMBDRIVE_FMU_INCLUDE_DIRS})

foreach(_fmu csfh combdrive)
  foreach(_program fuzz_fmi fmu_states)
    set(_target ${_program}_${_fmu})
    add_executable(${_target} tests/fuzz/${_program}.c ${_fuzz_sources_${_fmu}})
    add_dependencies(${_target} csfh_generate)
    target_include_directories(${_target} PRIVATE ${FMI_HEADERS_DIR} ${_fuzz_include_${_fmu}})
    target_compile_options(${_target} PRIVATE ${CSFH_WARNINGS} ${CSFH_FUZZ_FLAGS})
    # a hopeless step (fuzzed g = 1e20, a step of 1e300 s) fails at the same guard as in the
    # FMU, after 20000 integrator steps instead of 500000: seconds -> 0.1 s
    target_compile_definitions(${_target} PRIVATE MAX_STEPS_PER_CALL=20000L)
    target_link_options(${_target} PRIVATE ${CSFH_FUZZ_FLAGS})
    target_link_libraries(${_target} PRIVATE ${CSFH_FUZZ_CVODE} m)
  endforeach()
endforeach()

# the FMI 3.0 front-end (tests/fuzz/fuzz_fmi3.c): the same sources with fmu_src/fmu/fmi3/
foreach(_fmu csfh combdrive)
  set(_target fuzz_fmi3_${_fmu})
  set(_sources3 ${_fuzz_sources_${_fmu}})
  list(REMOVE_ITEM _sources3 ${CSFH_FMI2_FRONT_END})
  list(APPEND _sources3 ${CSFH_FMI3_FRONT_END})
  add_executable(${_target} tests/fuzz/fuzz_fmi3.c ${_sources3})
  add_dependencies(${_target} csfh_generate)
  target_include_directories(${_target} PRIVATE ${FMI_HEADERS_DIR} ${_fuzz_include_${_fmu}})
  target_compile_options(${_target} PRIVATE ${CSFH_WARNINGS} ${CSFH_FUZZ_FLAGS})
  target_compile_definitions(${_target} PRIVATE MAX_STEPS_PER_CALL=20000L)
  target_link_options(${_target} PRIVATE ${CSFH_FUZZ_FLAGS})
  target_link_libraries(${_target} PRIVATE ${CSFH_FUZZ_CVODE} m)
endforeach()

# the failed-allocation test (tests/fuzz/alloc_fail.c): every allocation of the FMU's code and of
# the SUNDIALS modules linked in goes through the driver's wrappers, which fail one in turn
set(_alloc_targets)
foreach(_fmu csfh combdrive)
  foreach(_fmi 2 3)
    set(_target alloc_fail_${_fmu}_fmi${_fmi})
    set(_sources ${_fuzz_sources_${_fmu}})
    if(_fmi EQUAL 3)
      list(REMOVE_ITEM _sources ${CSFH_FMI2_FRONT_END})
      list(APPEND _sources ${CSFH_FMI3_FRONT_END})
    endif()
    add_executable(${_target} tests/fuzz/alloc_fail.c tests/fuzz/alloc_fmi${_fmi}.c ${_sources})
    add_dependencies(${_target} csfh_generate)
    target_include_directories(${_target} PRIVATE ${FMI_HEADERS_DIR} ${_fuzz_include_${_fmu}})
    target_compile_options(${_target} PRIVATE ${CSFH_WARNINGS} ${CSFH_FUZZ_FLAGS})
    target_link_options(${_target} PRIVATE ${CSFH_FUZZ_FLAGS}
                        -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc)
    target_link_libraries(${_target} PRIVATE ${CSFH_FUZZ_CVODE} m)
    list(APPEND _alloc_targets ${_target})
  endforeach()
endforeach()

add_custom_target(csfh_fuzz)
add_dependencies(csfh_fuzz fuzz_fmi_csfh fuzz_fmi_combdrive fmu_states_csfh fmu_states_combdrive
                 fuzz_fmi3_csfh fuzz_fmi3_combdrive ${_alloc_targets})

# Fixed seeds, bounded: 2 x 320000 calls, about a minute for both FMUs on one core. Hangs are
# failures (the driver's alarm per sequence, then ctest's timeout).
set(_fuzz_env "ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1"
              "UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1")
add_test(NAME fuzz_fmi_csfh
         COMMAND fuzz_fmi_csfh --seeds 1 32 --sequences 50 --calls 200 --huge 8)
add_test(NAME fuzz_fmi_combdrive
         COMMAND fuzz_fmi_combdrive --seeds 1 32 --sequences 50 --calls 200 --huge 8)
# FMI 3.0: fewer calls (the shared instance is covered above), about 10 s per FMU
add_test(NAME fuzz_fmi3_csfh COMMAND fuzz_fmi3_csfh --seeds 1 8 --sequences 25 --calls 150)
add_test(NAME fuzz_fmi3_combdrive COMMAND fuzz_fmi3_combdrive --seeds 1 8 --sequences 25 --calls 150)
add_test(NAME fmu_states_csfh COMMAND fmu_states_csfh)
add_test(NAME fmu_states_combdrive COMMAND fmu_states_combdrive)
set_tests_properties(fuzz_fmi_csfh fuzz_fmi_combdrive fuzz_fmi3_csfh fuzz_fmi3_combdrive
                     fmu_states_csfh fmu_states_combdrive PROPERTIES
                     LABELS fuzz TIMEOUT 300 ENVIRONMENT "${_fuzz_env}")
# every allocation of a representative run failed in turn (a child process each), then all of
# SUNDIALS' at once: seconds per FMU and FMI version
foreach(_target IN LISTS _alloc_targets)
  add_test(NAME ${_target} COMMAND ${_target})
endforeach()
set_tests_properties(${_alloc_targets} PROPERTIES
                     LABELS alloc TIMEOUT 300 ENVIRONMENT "${_fuzz_env}")
