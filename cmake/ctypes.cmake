# The harness's ctypes libraries (the core, the batch master), for the host and for every cross
# build (cmake/platforms.cmake), so that each platform's wheel (tools/build_wheels.sh) carries its
# own.
#
#   csfh_add_ctypes_library(TARGET NAME name SOURCES ...)
#       a shared library exporting only what its header marks (CSFH_API, CSFH_BATCH_API), named
#       as csfh/paths.py looks for it: lib<name>.so (Linux), <name>.dll (Windows),
#       lib<name>.dylib (macOS); a cross build puts it into ${CMAKE_BINARY_DIR}/lib/, stripped.
#       The Linux cross build links against glibc 2.17 like the FMU binaries.

function(csfh_add_ctypes_library target)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES" ${ARGN})
  add_library(${target} SHARED ${ARG_SOURCES})
  set_target_properties(${target} PROPERTIES OUTPUT_NAME ${ARG_NAME})
  target_compile_options(${target} PRIVATE ${CSFH_WARNINGS})
  if(WIN32)
    # ctypes loads <name>.dll by its path; no import library, nothing links against it
    set_target_properties(${target} PROPERTIES PREFIX "" IMPORT_PREFIX "" IMPORT_SUFFIX ".dll.a")
  else()
    target_link_libraries(${target} PRIVATE m)
  endif()
  if(APPLE)
    target_link_options(${target} PRIVATE -Wl,-install_name,@rpath/lib${ARG_NAME}.dylib)
  elseif(NOT WIN32)
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
  if(CSFH_CROSS_BUILD)
    set_target_properties(${target} PROPERTIES
      LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib
      RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib
      ARCHIVE_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/lib)
    target_link_options(${target} PRIVATE -s)  # zig keeps debug information otherwise
  endif()
endfunction()

# the file names of the ctypes libraries on each FMI platform (the cross builds' byproducts)
function(csfh_ctypes_file_names out platform)
  set(names)
  foreach(name csfh_core csfh_batch)
    if(platform STREQUAL "win64")
      list(APPEND names ${name}.dll)
    elseif(platform STREQUAL "darwin64")
      list(APPEND names lib${name}.dylib)
    else()
      list(APPEND names lib${name}.so)
    endif()
  endforeach()
  set(${out} ${names} PARENT_SCOPE)
endfunction()
