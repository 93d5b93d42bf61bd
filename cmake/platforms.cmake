# The FMUs' binaries for every platform, cross-compiled with zig (the `ziglang` package on PyPI).
#
#   CSFH_PLATFORMS = all    linux64  x86_64-linux-gnu.2.17 (runs on glibc >= 2.17: CentOS 7, RHEL 8,
#                                    Ubuntu 20.04 and later)
#                           win64    x86_64-windows-gnu (Universal CRT, i.e. Windows 10 and later,
#                                    or the redistributable on older Windows)
#                           darwin64 x86_64-macos and aarch64-macos, one universal (fat) binary,
#                                    for macOS 11 and later (the first with arm64; zig 0.17.1's
#                                    default is macOS 15)
#                  = host   the host compiler's linux64 binary only (no zig needed)
#                  = auto   all where zig is found, else host (the default)
#   CSFH_ZIG                the zig executable (default: the ziglang Python package of the Python
#                           that runs the build, else zig on PATH)
#
# Each platform (each darwin slice) is a cross build of this same project in
# build/platforms/<slice> (CSFH_CROSS_BUILD: SUNDIALS, the FMU binaries, the test importers),
# with the same SUNDIALS source, the same FMI headers and the same flags, run by ExternalProject;
# each also makes the harness's ctypes libraries (cmake/ctypes.cmake) in <cross build>/lib/.
# Provides csfh_platform_binaries(OUT MODEL_IDENTIFIER id): "platform=file[,file]" entries for
# tools/fmu_package.py and the targets that build them (CSFH_PLATFORM_TARGETS).

set(CSFH_PLATFORMS "auto" CACHE STRING "Platforms of the FMU binaries: all (zig cross builds), host, auto")
set_property(CACHE CSFH_PLATFORMS PROPERTY STRINGS auto all host)
set(CSFH_ZIG "" CACHE FILEPATH "The zig executable for the cross builds (default: Python package ziglang, else PATH)")

if(NOT CSFH_ZIG)
  execute_process(
    COMMAND ${Python3_EXECUTABLE} -c
            "import ziglang, os; print(os.path.join(os.path.dirname(ziglang.__file__), 'zig'))"
    OUTPUT_VARIABLE _zig OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE _zig_rc ERROR_QUIET)
  if(_zig_rc EQUAL 0 AND EXISTS "${_zig}")
    set(CSFH_ZIG "${_zig}" CACHE FILEPATH "The zig executable for the cross builds" FORCE)
  else()
    find_program(_zig_path zig)
    if(_zig_path)
      set(CSFH_ZIG "${_zig_path}" CACHE FILEPATH "The zig executable for the cross builds" FORCE)
    endif()
  endif()
endif()

set(_platforms "${CSFH_PLATFORMS}")
if(_platforms STREQUAL "auto")
  if(CSFH_ZIG)
    set(_platforms all)
  else()
    set(_platforms host)
    message(STATUS "Platforms: host only (no zig: pip install ziglang, or -DCSFH_ZIG=...)")
  endif()
endif()
if(_platforms STREQUAL "all" AND NOT CSFH_ZIG)
  message(FATAL_ERROR "CSFH_PLATFORMS=all needs zig: pip install ziglang, or pass -DCSFH_ZIG=<zig>")
endif()
if(NOT _platforms MATCHES "^(all|host)$")
  message(FATAL_ERROR "CSFH_PLATFORMS must be all, host or auto, got '${CSFH_PLATFORMS}'")
endif()
set(CSFH_PLATFORMS_BUILT ${_platforms})

# slice: platform, zig target, CMAKE_SYSTEM_NAME, CMAKE_SYSTEM_PROCESSOR
set(_csfh_slices
  "linux64|linux64|x86_64-linux-gnu.2.17|Linux|x86_64"
  "win64|win64|x86_64-windows-gnu|Windows|AMD64"
  "darwin64-x86_64|darwin64|x86_64-macos.11.0|Darwin|x86_64"
  "darwin64-arm64|darwin64|aarch64-macos.11.0|Darwin|arm64")
set(CSFH_PLATFORM_TARGETS)

# the FMI 3.0 platform tuple of a slice
function(_csfh_fmu3_tuple out slice)
  if(slice STREQUAL "linux64")
    set(${out} x86_64-linux PARENT_SCOPE)
  elseif(slice STREQUAL "win64")
    set(${out} x86_64-windows PARENT_SCOPE)
  elseif(slice STREQUAL "darwin64-x86_64")
    set(${out} x86_64-darwin PARENT_SCOPE)
  else()
    set(${out} aarch64-darwin PARENT_SCOPE)
  endif()
endfunction()

if(_platforms STREQUAL "all")
  include(ExternalProject)
  execute_process(COMMAND "${CSFH_ZIG}" version OUTPUT_VARIABLE _zig_version
                  OUTPUT_STRIP_TRAILING_WHITESPACE)
  message(STATUS "Platforms: linux64 (glibc 2.17), win64, darwin64 (x86_64 + arm64) with zig ${_zig_version}: ${CSFH_ZIG}")
  set(_wrappers ${CMAKE_BINARY_DIR}/platforms/zig)
  # zig as a compiler CMake can call: one small script per tool and target
  function(_csfh_zig_wrapper name text)
    file(WRITE ${_wrappers}/tmp/${name} "#!/bin/sh\n${text}\n")
    file(COPY ${_wrappers}/tmp/${name} DESTINATION ${_wrappers}
         FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE
                          WORLD_READ WORLD_EXECUTE)
  endfunction()
  _csfh_zig_wrapper(zig-ar "exec \"${CSFH_ZIG}\" ar \"$@\"")
  _csfh_zig_wrapper(zig-ranlib "exec \"${CSFH_ZIG}\" ranlib \"$@\"")
  get_property(CSFH_FMU_MODEL_IDENTIFIERS GLOBAL PROPERTY CSFH_FMU_MODEL_IDENTIFIERS)
  list(REMOVE_DUPLICATES CSFH_FMU_MODEL_IDENTIFIERS)
  foreach(slice_spec IN LISTS _csfh_slices)
    string(REPLACE "|" ";" slice_spec "${slice_spec}")
    list(GET slice_spec 0 slice)
    list(GET slice_spec 2 triple)
    list(GET slice_spec 3 system)
    list(GET slice_spec 4 processor)
    _csfh_zig_wrapper(${triple}-cc "exec \"${CSFH_ZIG}\" cc -target ${triple} \"$@\"")
    list(GET slice_spec 1 platform)
    set(suffix .so)
    if(platform STREQUAL "win64")
      set(suffix .dll)
    elseif(platform STREQUAL "darwin64")
      set(suffix .dylib)
    endif()
    set(byproducts)
    foreach(id IN LISTS CSFH_FMU_MODEL_IDENTIFIERS)
      list(APPEND byproducts ${CMAKE_BINARY_DIR}/platforms/${slice}/binaries/${id}/${platform}/${id}${suffix})
      # the FMI 3.0 binaries (fmu.cmake: binaries3/<id>/<platform tuple>/)
      _csfh_fmu3_tuple(tuple ${slice})
      list(APPEND byproducts ${CMAKE_BINARY_DIR}/platforms/${slice}/binaries3/${id}/${tuple}/${id}${suffix})
    endforeach()
    # the ctypes libraries (cmake/ctypes.cmake) in <cross build>/lib/
    csfh_ctypes_file_names(libraries ${platform})
    foreach(library IN LISTS libraries)
      list(APPEND byproducts ${CMAKE_BINARY_DIR}/platforms/${slice}/lib/${library})
    endforeach()
    # a cross build not configured for this target triple (CSFH_CROSS_TRIPLE, in its cache) is
    # configured afresh: on a compiler change CMake drops the cache's variables, the -D
    # arguments included
    set(cache ${CMAKE_BINARY_DIR}/platforms/${slice}/CMakeCache.txt)
    if(EXISTS ${cache})
      file(STRINGS ${cache} configured REGEX "^CSFH_CROSS_TRIPLE:")
      if(NOT configured MATCHES "=${triple}$")
        file(REMOVE ${cache})
      endif()
    endif()
    ExternalProject_Add(csfh_platform_${slice}
      SOURCE_DIR ${PROJECT_SOURCE_DIR}
      BINARY_DIR ${CMAKE_BINARY_DIR}/platforms/${slice}
      CMAKE_ARGS
        -DCSFH_CROSS_BUILD=ON -DCSFH_CROSS_TRIPLE=${triple} -DCSFH_BUILD_TESTS=OFF
        -DCSFH_BUILD_BENCHMARKS=OFF
        -DCMAKE_BUILD_TYPE=Release
        -DCMAKE_SYSTEM_NAME=${system} -DCMAKE_SYSTEM_PROCESSOR=${processor}
        -DCMAKE_C_COMPILER=${_wrappers}/${triple}-cc
        -DCMAKE_AR=${_wrappers}/zig-ar -DCMAKE_RANLIB=${_wrappers}/zig-ranlib
        -DPython3_EXECUTABLE=${Python3_EXECUTABLE}
        -DFMI_HEADERS_DIR=${FMI_HEADERS_DIR}
        -DCSFH_SUNDIALS_SOURCE_DIR=${CSFH_SUNDIALS_SOURCE_DIR}
      BUILD_ALWAYS ON
      BUILD_BYPRODUCTS ${byproducts}
      INSTALL_COMMAND ""
      USES_TERMINAL_CONFIGURE ON  # one cross build at a time (each uses every core)
      USES_TERMINAL_BUILD ON)
    list(APPEND CSFH_PLATFORM_TARGETS csfh_platform_${slice})
  endforeach()

  # darwin64's ctypes libraries as universal (x86_64 + arm64) files, as the FMU binary:
  # build/platforms/darwin64/lib/ (the macOS wheel's, tools/build_wheels.sh)
  csfh_ctypes_file_names(libraries darwin64)
  set(fat_libraries)
  foreach(library IN LISTS libraries)
    set(fat ${CMAKE_BINARY_DIR}/platforms/darwin64/lib/${library})
    set(thin ${CMAKE_BINARY_DIR}/platforms/darwin64-x86_64/lib/${library}
             ${CMAKE_BINARY_DIR}/platforms/darwin64-arm64/lib/${library})
    add_custom_command(
      OUTPUT ${fat}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_BINARY_DIR}/platforms/darwin64/lib
      COMMAND Python3::Interpreter ${PROJECT_SOURCE_DIR}/tools/macho_fat.py ${fat} ${thin}
      DEPENDS csfh_platform_darwin64-x86_64 csfh_platform_darwin64-arm64 ${thin}
              ${PROJECT_SOURCE_DIR}/tools/macho_fat.py
      COMMENT "Joining the darwin64 slices of ${library}"
      VERBATIM)
    list(APPEND fat_libraries ${fat})
  endforeach()
  add_custom_target(csfh_darwin64_libraries ALL DEPENDS ${fat_libraries})
endif()

# "platform=file[,file...]" for tools/fmu_package.py: the binaries of model `id` (host_file: the
# host build's binary, used when CSFH_PLATFORMS is host)
function(csfh_platform_binaries out id host_file)
  if(CSFH_PLATFORMS_BUILT STREQUAL "host")
    set(${out} "${CSFH_FMU_PLATFORM}=${host_file}" PARENT_SCOPE)
    return()
  endif()
  set(p ${CMAKE_BINARY_DIR}/platforms)
  set(${out}
    "linux64=${p}/linux64/binaries/${id}/linux64/${id}.so"
    "win64=${p}/win64/binaries/${id}/win64/${id}.dll"
    "darwin64=${p}/darwin64-x86_64/binaries/${id}/darwin64/${id}.dylib,${p}/darwin64-arm64/binaries/${id}/darwin64/${id}.dylib"
    PARENT_SCOPE)
endfunction()

# "tuple=file" for tools/fmu_package.py: the FMI 3.0 binaries of model `id` (one per platform
# tuple; darwin: x86_64-darwin and aarch64-darwin, no universal binary)
function(csfh_platform_binaries3 out id host_file)
  if(CSFH_PLATFORMS_BUILT STREQUAL "host")
    set(${out} "${CSFH_FMU3_PLATFORM}=${host_file}" PARENT_SCOPE)
    return()
  endif()
  set(p ${CMAKE_BINARY_DIR}/platforms)
  set(${out}
    "x86_64-linux=${p}/linux64/binaries3/${id}/x86_64-linux/${id}.so"
    "x86_64-windows=${p}/win64/binaries3/${id}/x86_64-windows/${id}.dll"
    "x86_64-darwin=${p}/darwin64-x86_64/binaries3/${id}/x86_64-darwin/${id}.dylib"
    "aarch64-darwin=${p}/darwin64-arm64/binaries3/${id}/aarch64-darwin/${id}.dylib"
    PARENT_SCOPE)
endfunction()
