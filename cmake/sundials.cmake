# SUNDIALS 6.4.1 compiled from Debian's source package, with our flags, into every FMU binary.
#
# Debian's libsundials-dev is built without optimisation (its package build drops -O2), which
# makes the co-simulation loop about 3x slower (benchmarks/bench_sundials_build.py). We therefore
# compile the few SUNDIALS modules the FMUs need ourselves, from the source of the same release
# (Debian bookworm's `sundials` source package), with our own fixed configuration header
# (fmu_src/sundials_config/), static and hidden. The same file lists serve the host build, every
# cross-compiled platform (cmake/platforms.cmake) and the FMU's sources/ (cmake/fmu.cmake).
#
# Where the source comes from (nothing of SUNDIALS is committed):
#   CSFH_SUNDIALS_SOURCE_DIR   an unpacked SUNDIALS 6.4.1 source tree, if you have one;
#   otherwise `apt-get source sundials` (needs a deb-src entry for bookworm and dpkg-dev:
#   tools/setup.sh adds both) into CSFH_SUNDIALS_CACHE (default: .cache/sundials in the source
#   tree, gitignored, shared by every build directory), once; later configures reuse it.
#
# Provides:
#   CSFH_SUNDIALS_SOURCE_DIR           the unpacked tree
#   CSFH_SUNDIALS_CONFIG_DIR           our sundials/sundials_config.h, sundials/sundials_export.h,
#                                      sundials/csfh_sundials_alloc.h
#   CSFH_SUNDIALS_ALLOCATOR            our allocator for SUNDIALS (csfh_sundials_alloc.c), a source
#                                      of the core module
#   csfh_sundials_sources(OUT MODULES m...)   absolute paths of the modules' .c files
#   csfh_sundials_headers(OUT MODULES m...)   their headers: (absolute path, path under an
#                                             include root) pairs, see the function
#   csfh_add_sundials_library(TARGET MODULES m...)   a static library of the modules
# Modules: core nvecserial sunmatdense sunmatband sunlinsoldense sunnlsnewton sunnlsfixedpoint cvode
#          arkode_erk (ARKODE with its explicit Runge-Kutta stepper ERKStep).

set(CSFH_SUNDIALS_VERSION 6.4.1)
set(CSFH_SUNDIALS_SOURCE_DIR "" CACHE PATH "An unpacked SUNDIALS ${CSFH_SUNDIALS_VERSION} source tree (default: apt-get source sundials into CSFH_SUNDIALS_CACHE)")
set(CSFH_SUNDIALS_CACHE "${CMAKE_CURRENT_SOURCE_DIR}/.cache/sundials" CACHE PATH "Where the SUNDIALS source package is downloaded and unpacked once")
set(CSFH_SUNDIALS_CONFIG_DIR "${CMAKE_CURRENT_SOURCE_DIR}/fmu_src/sundials_config")
# our configuration header routes SUNDIALS' allocations through this file (compiled with our
# warnings, not SUNDIALS' flags: csfh_add_sundials_library)
set(CSFH_SUNDIALS_ALLOCATOR "${CSFH_SUNDIALS_CONFIG_DIR}/csfh_sundials_alloc.c")

# --------------------------------------------------------------------------------------------
# the source tree

function(_csfh_sundials_check dir result)
  set(${result} FALSE PARENT_SCOPE)
  if(EXISTS "${dir}/CMakeLists.txt" AND EXISTS "${dir}/src/cvode/cvode.c")
    file(STRINGS "${dir}/CMakeLists.txt" _v REGEX "^set\\(PACKAGE_VERSION_(MAJOR|MINOR|PATCH) ")
    string(REGEX REPLACE "[^0-9;]" "" _v "${_v}")
    list(JOIN _v "." _v)
    if(_v STREQUAL CSFH_SUNDIALS_VERSION)
      set(${result} TRUE PARENT_SCOPE)
    else()
      message(WARNING "SUNDIALS source ${dir} is version ${_v}, not ${CSFH_SUNDIALS_VERSION}")
    endif()
  endif()
endfunction()

function(_csfh_sundials_fetch cache result)
  set(unpacked "${cache}/sundials-${CSFH_SUNDIALS_VERSION}")
  _csfh_sundials_check("${unpacked}" ok)
  if(ok)
    set(${result} "${unpacked}" PARENT_SCOPE)
    return()
  endif()
  find_program(CSFH_APT_GET apt-get)
  find_program(CSFH_DPKG_SOURCE dpkg-source)
  if(NOT CSFH_APT_GET OR NOT CSFH_DPKG_SOURCE)
    message(FATAL_ERROR
      "SUNDIALS ${CSFH_SUNDIALS_VERSION} is compiled from Debian's source package, which needs "
      "apt-get and dpkg-source (apt-get install dpkg-dev; tools/setup.sh does it), or pass "
      "-DCSFH_SUNDIALS_SOURCE_DIR=<an unpacked sundials-${CSFH_SUNDIALS_VERSION} tree>")
  endif()
  set(work "${cache}/download")
  file(REMOVE_RECURSE "${work}")
  file(MAKE_DIRECTORY "${work}")
  message(STATUS "Fetching Debian's SUNDIALS source package into ${cache}")
  execute_process(
    COMMAND ${CSFH_APT_GET} source -qq sundials
    WORKING_DIRECTORY "${work}"
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  file(GLOB trees LIST_DIRECTORIES true "${work}/sundials-${CSFH_SUNDIALS_VERSION}*")
  set(tree "")
  foreach(t IN LISTS trees)
    if(IS_DIRECTORY "${t}")
      set(tree "${t}")
    endif()
  endforeach()
  if(NOT rc EQUAL 0 OR NOT tree)
    message(FATAL_ERROR
      "apt-get source sundials failed (${rc}):\n${out}${err}\n"
      "It needs a deb-src entry for Debian bookworm (tools/setup.sh adds "
      "/etc/apt/sources.list.d/debian-src.sources, then apt-get update) and dpkg-dev; or pass "
      "-DCSFH_SUNDIALS_SOURCE_DIR=<an unpacked sundials-${CSFH_SUNDIALS_VERSION} tree>")
  endif()
  _csfh_sundials_check("${tree}" ok)
  if(NOT ok)
    message(FATAL_ERROR "apt-get source sundials unpacked ${tree}, which is not SUNDIALS ${CSFH_SUNDIALS_VERSION}")
  endif()
  file(REMOVE_RECURSE "${unpacked}")
  file(RENAME "${tree}" "${unpacked}")
  file(REMOVE_RECURSE "${work}")
  set(${result} "${unpacked}" PARENT_SCOPE)
endfunction()

if(CSFH_SUNDIALS_SOURCE_DIR)
  _csfh_sundials_check("${CSFH_SUNDIALS_SOURCE_DIR}" _ok)
  if(NOT _ok)
    message(FATAL_ERROR "CSFH_SUNDIALS_SOURCE_DIR=${CSFH_SUNDIALS_SOURCE_DIR} is not a SUNDIALS ${CSFH_SUNDIALS_VERSION} source tree")
  endif()
else()
  _csfh_sundials_fetch("${CSFH_SUNDIALS_CACHE}" _dir)
  set(CSFH_SUNDIALS_SOURCE_DIR "${_dir}" CACHE PATH "An unpacked SUNDIALS ${CSFH_SUNDIALS_VERSION} source tree" FORCE)
endif()
message(STATUS "SUNDIALS ${CSFH_SUNDIALS_VERSION} source: ${CSFH_SUNDIALS_SOURCE_DIR}")

# --------------------------------------------------------------------------------------------
# the modules: .c files (relative to src/) and public headers (relative to include/)

set(_csfh_sundials_core_SOURCES
  sundials/sundials_math.c sundials/sundials_nvector.c sundials/sundials_matrix.c
  sundials/sundials_linearsolver.c sundials/sundials_nonlinearsolver.c sundials/sundials_context.c
  sundials/sundials_logger.c sundials/sundials_dense.c sundials/sundials_nvector_senswrapper.c)
set(_csfh_sundials_core_PRIVATE
  sundials/sundials_context_impl.h sundials/sundials_logger_impl.h sundials/sundials_hashmap.h
  sundials/sundials_utils.h sundials/sundials_debug.h)
set(_csfh_sundials_core_HEADERS
  sundials/sundials_types.h sundials/sundials_math.h sundials/sundials_nvector.h
  sundials/sundials_matrix.h sundials/sundials_linearsolver.h sundials/sundials_nonlinearsolver.h
  sundials/sundials_context.h sundials/sundials_logger.h sundials/sundials_profiler.h
  sundials/sundials_dense.h sundials/sundials_direct.h sundials/sundials_iterative.h
  sundials/sundials_nvector_senswrapper.h)

set(_csfh_sundials_nvecserial_SOURCES nvector/serial/nvector_serial.c)
set(_csfh_sundials_nvecserial_HEADERS nvector/nvector_serial.h)
set(_csfh_sundials_sunmatdense_SOURCES sunmatrix/dense/sunmatrix_dense.c)
set(_csfh_sundials_sunmatdense_HEADERS sunmatrix/sunmatrix_dense.h)
# (the linear solver interfaces of CVODE and ARKODE refer to the band matrix)
set(_csfh_sundials_sunmatband_SOURCES sunmatrix/band/sunmatrix_band.c)
set(_csfh_sundials_sunmatband_HEADERS sunmatrix/sunmatrix_band.h)
set(_csfh_sundials_sunlinsoldense_SOURCES sunlinsol/dense/sunlinsol_dense.c)
set(_csfh_sundials_sunlinsoldense_HEADERS sunlinsol/sunlinsol_dense.h)
set(_csfh_sundials_sunnlsnewton_SOURCES sunnonlinsol/newton/sunnonlinsol_newton.c)
set(_csfh_sundials_sunnlsnewton_HEADERS sunnonlinsol/sunnonlinsol_newton.h)
set(_csfh_sundials_sunnlsfixedpoint_SOURCES sunnonlinsol/fixedpoint/sunnonlinsol_fixedpoint.c)
set(_csfh_sundials_sunnlsfixedpoint_HEADERS sunnonlinsol/sunnonlinsol_fixedpoint.h)

set(_csfh_sundials_cvode_SOURCES
  cvode/cvode.c cvode/cvode_io.c cvode/cvode_ls.c cvode/cvode_nls.c cvode/cvode_proj.c)
set(_csfh_sundials_cvode_PRIVATE cvode/cvode_impl.h cvode/cvode_ls_impl.h cvode/cvode_proj_impl.h)
set(_csfh_sundials_cvode_HEADERS
  cvode/cvode.h cvode/cvode_ls.h cvode/cvode_proj.h sunmatrix/sunmatrix_sparse.h)

set(_csfh_sundials_arkode_erk_SOURCES
  arkode/arkode.c arkode/arkode_adapt.c arkode/arkode_butcher.c arkode/arkode_butcher_erk.c
  arkode/arkode_erkstep.c arkode/arkode_erkstep_io.c arkode/arkode_interp.c arkode/arkode_io.c
  arkode/arkode_root.c)
set(_csfh_sundials_arkode_erk_PRIVATE
  arkode/arkode_impl.h arkode/arkode_adapt_impl.h arkode/arkode_erkstep_impl.h
  arkode/arkode_interp_impl.h arkode/arkode_root_impl.h arkode/arkode_butcher_erk.def)
set(_csfh_sundials_arkode_erk_HEADERS
  arkode/arkode.h arkode/arkode_butcher.h arkode/arkode_butcher_erk.h
  arkode/arkode_butcher_dirk.h arkode/arkode_erkstep.h)

set(CSFH_SUNDIALS_MODULES core nvecserial sunmatdense sunmatband sunlinsoldense sunnlsnewton
    sunnlsfixedpoint cvode arkode_erk)

# OUT: absolute paths of the .c files of MODULES (the core module's include our allocator)
function(csfh_sundials_sources out)
  cmake_parse_arguments(ARG "" "" "MODULES" ${ARGN})
  set(files)
  foreach(m IN LISTS ARG_MODULES)
    if(NOT m IN_LIST CSFH_SUNDIALS_MODULES)
      message(FATAL_ERROR "unknown SUNDIALS module ${m} (known: ${CSFH_SUNDIALS_MODULES})")
    endif()
    foreach(f IN LISTS _csfh_sundials_${m}_SOURCES)
      list(APPEND files "${CSFH_SUNDIALS_SOURCE_DIR}/src/${f}")
    endforeach()
    if(m STREQUAL "core")
      list(APPEND files "${CSFH_SUNDIALS_ALLOCATOR}")
    endif()
  endforeach()
  set(${out} ${files} PARENT_SCOPE)
endfunction()

# OUT_PRIVATE: absolute paths of the private headers (.h/.def next to the .c files: a source
# build keeps them beside the flattened .c files); OUT_PUBLIC: absolute paths of the public
# headers, each under include/<module dir>/ (a source build keeps that relative path)
function(csfh_sundials_headers out_private out_public)
  cmake_parse_arguments(ARG "" "" "MODULES" ${ARGN})
  set(private)
  set(public)
  foreach(m IN LISTS ARG_MODULES)
    foreach(f IN LISTS _csfh_sundials_${m}_PRIVATE)
      list(APPEND private "${CSFH_SUNDIALS_SOURCE_DIR}/src/${f}")
    endforeach()
    foreach(f IN LISTS _csfh_sundials_${m}_HEADERS)
      list(APPEND public "${CSFH_SUNDIALS_SOURCE_DIR}/include/${f}")
    endforeach()
  endforeach()
  set(${out_private} ${private} PARENT_SCOPE)
  set(${out_public} ${public} PARENT_SCOPE)
endfunction()

# the include directories a target compiling the sources of MODULES needs (ours first)
function(csfh_sundials_include_dirs out)
  cmake_parse_arguments(ARG "" "" "MODULES" ${ARGN})
  set(dirs "${CSFH_SUNDIALS_CONFIG_DIR}" "${CSFH_SUNDIALS_SOURCE_DIR}/include")
  foreach(m IN LISTS ARG_MODULES)
    foreach(f IN LISTS _csfh_sundials_${m}_SOURCES)
      get_filename_component(d "${CSFH_SUNDIALS_SOURCE_DIR}/src/${f}" DIRECTORY)
      list(APPEND dirs "${d}")
    endforeach()
  endforeach()
  list(APPEND dirs "${CSFH_SUNDIALS_SOURCE_DIR}/src/sundials")
  list(REMOVE_DUPLICATES dirs)
  set(${out} ${dirs} PARENT_SCOPE)
endfunction()

# a static library of MODULES, optimised whatever the build type, hidden; its users get our
# configuration header and SUNDIALS' public headers
function(csfh_add_sundials_library target)
  cmake_parse_arguments(ARG "" "" "MODULES" ${ARGN})
  csfh_sundials_sources(sources MODULES ${ARG_MODULES})
  csfh_sundials_include_dirs(dirs MODULES ${ARG_MODULES})
  list(REMOVE_ITEM sources "${CSFH_SUNDIALS_ALLOCATOR}")
  add_library(${target}_allocator OBJECT "${CSFH_SUNDIALS_ALLOCATOR}")
  target_include_directories(${target}_allocator PRIVATE "${CSFH_SUNDIALS_CONFIG_DIR}")
  target_compile_options(${target}_allocator PRIVATE ${CSFH_WARNINGS})
  set_target_properties(${target}_allocator PROPERTIES C_VISIBILITY_PRESET hidden
                        POSITION_INDEPENDENT_CODE ON)
  add_library(${target} STATIC ${sources} $<TARGET_OBJECTS:${target}_allocator>)
  target_include_directories(${target} PRIVATE ${dirs})
  target_include_directories(${target} SYSTEM PUBLIC
    "${CSFH_SUNDIALS_CONFIG_DIR}" "${CSFH_SUNDIALS_SOURCE_DIR}/include")
  set_target_properties(${target} PROPERTIES C_VISIBILITY_PRESET hidden POSITION_INDEPENDENT_CODE ON)
  # -O2 at least (Release gives -O3): the point of building it ourselves
  if(NOT CMAKE_BUILD_TYPE MATCHES "^(Release|RelWithDebInfo|MinSizeRel)$")
    target_compile_options(${target} PRIVATE -O2)
  endif()
  # SUNDIALS' own code is not ours to warn about
  target_compile_options(${target} PRIVATE -w)
  if(NOT WIN32)
    target_link_libraries(${target} PUBLIC m)
  endif()
endfunction()
