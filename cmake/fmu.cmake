# FMU binaries, test importers and FMU packages.
#
#   CSFH_FMU_PLATFORM                 linux64 | win64 | darwin64: the FMI 2.0 platform of this
#                                     build's compiler (a cross build: cmake/platforms.cmake)
#   CSFH_FMU3_PLATFORM                x86_64-linux | x86_64-windows | x86_64-darwin |
#                                     aarch64-darwin: the FMI 3.0 platform tuple of this build
#   csfh_add_fmu_binary(TARGET MODEL_IDENTIFIER id SOURCES ... [INCLUDE_DIRS ...] [LINK ...]
#                       [FMI_VERSION 2|3])
#       the FMU's shared library for this platform, exporting only the fmi2* (FMI 3.0: fmi3*)
#       functions, into ${CMAKE_BINARY_DIR}/binaries/<id>/<platform>/ (FMI 3.0:
#       ${CMAKE_BINARY_DIR}/binaries3/<id>/<platform tuple>/)
#   csfh_add_fmu_objects(TARGET SOURCES ... [INCLUDE_DIRS ...] [LINK ...])
#       the FMI-independent part of an FMU (model, instance, stepper) compiled once, as an object
#       library that the FMI 2.0 and FMI 3.0 binaries both link (LINK TARGET), each with its own
#       front-end (fmi2_glue.c, fmi3_glue.c)
#   csfh_add_test_importer(TARGET SOURCES ... [LINK ...])
#       a C importer (an executable that loads FMU binaries, portable between POSIX and Windows):
#       built by the host build and by every cross build, so the same importer runs the FMU of
#       each platform (win64: under wine, tests/fmu/test_platforms.py)
#   csfh_add_fmu_package(NAME ...)   build/<NAME>.fmu, see below
#   csfh_add_fmu3_package(NAME ...)  build/fmi3/<NAME>.fmu, the FMI 3.0 build, see below

# the FMI 2.0 headers: fmpy's, or FMI_HEADERS_DIR
if(NOT FMI_HEADERS_DIR)
  execute_process(
    COMMAND ${Python3_EXECUTABLE} -c
            "import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), 'c-code'))"
    OUTPUT_VARIABLE FMI_HEADERS_DIR OUTPUT_STRIP_TRAILING_WHITESPACE
    RESULT_VARIABLE _fmpy_result)
  if(NOT _fmpy_result EQUAL 0)
    message(FATAL_ERROR "The FMI 2.0 headers come from the installed fmpy package: "
                        "pip install fmpy, or pass -DFMI_HEADERS_DIR=<dir with fmi2Functions.h>")
  endif()
endif()
foreach(_header fmi2Functions.h fmi3Functions.h)
  if(NOT EXISTS ${FMI_HEADERS_DIR}/${_header})
    message(FATAL_ERROR "${_header} not found in FMI_HEADERS_DIR=${FMI_HEADERS_DIR}")
  endif()
endforeach()
message(STATUS "FMI 2.0 headers: ${FMI_HEADERS_DIR}")

if(APPLE)
  # an FMU binary is a dynamic library (dlopen-ed like any), not a Mach-O bundle
  string(REPLACE "-bundle" "-dynamiclib" CMAKE_SHARED_MODULE_CREATE_C_FLAGS
         "${CMAKE_SHARED_MODULE_CREATE_C_FLAGS}")
endif()
if(WIN32)
  set(CSFH_FMU_PLATFORM win64)
  set(_fmu3_system windows)
elseif(APPLE)
  set(CSFH_FMU_PLATFORM darwin64)
  set(_fmu3_system darwin)
else()
  set(CSFH_FMU_PLATFORM linux64)
  set(_fmu3_system linux)
endif()
if(CMAKE_SYSTEM_PROCESSOR MATCHES "^(arm64|aarch64|ARM64)$")
  set(CSFH_FMU3_PLATFORM aarch64-${_fmu3_system})
else()
  set(CSFH_FMU3_PLATFORM x86_64-${_fmu3_system})
endif()

function(csfh_add_fmu_binary target)
  cmake_parse_arguments(ARG "" "MODEL_IDENTIFIER;FMI_VERSION" "SOURCES;INCLUDE_DIRS;LINK" ${ARGN})
  add_library(${target} MODULE ${ARG_SOURCES})
  if(ARG_FMI_VERSION STREQUAL "3")
    set(output_dir ${CMAKE_BINARY_DIR}/binaries3/${ARG_MODEL_IDENTIFIER}/${CSFH_FMU3_PLATFORM})
    set(exports ${PROJECT_SOURCE_DIR}/fmu_src/fmu/fmi3/exports.map)
  else()
    set(output_dir ${CMAKE_BINARY_DIR}/binaries/${ARG_MODEL_IDENTIFIER}/${CSFH_FMU_PLATFORM})
    set(exports ${PROJECT_SOURCE_DIR}/fmu_src/fmu/fmi2/exports.map)
  endif()
  set_target_properties(${target} PROPERTIES
    OUTPUT_NAME ${ARG_MODEL_IDENTIFIER} PREFIX ""
    LIBRARY_OUTPUT_DIRECTORY ${output_dir})
  target_include_directories(${target} PRIVATE ${FMI_HEADERS_DIR} ${ARG_INCLUDE_DIRS})
  target_compile_options(${target} PRIVATE ${CSFH_WARNINGS})
  target_link_libraries(${target} PRIVATE ${ARG_LINK})
  set_property(GLOBAL APPEND PROPERTY CSFH_FMU_MODEL_IDENTIFIERS ${ARG_MODEL_IDENTIFIER})
  if(CSFH_CROSS_BUILD)
    target_link_options(${target} PRIVATE -s)  # zig keeps debug information otherwise
  endif()
  if(WIN32)
    # exports: the functions FMI2_Export marks __declspec(dllexport) in fmi2Functions.h, only
    set_target_properties(${target} PROPERTIES SUFFIX ".dll")
  elseif(APPLE)
    # exports: the fmi2* functions (default visibility), everything else is hidden
    set_target_properties(${target} PROPERTIES SUFFIX ".dylib")
    target_link_options(${target} PRIVATE -Wl,-install_name,@rpath/${ARG_MODEL_IDENTIFIER}.dylib)
    target_link_libraries(${target} PRIVATE m)
  else()
    # export only the fmi2* functions; keep the static SUNDIALS symbols inside
    target_link_libraries(${target} PRIVATE m)
    target_link_options(${target} PRIVATE
      -Wl,--version-script=${exports} -Wl,--no-undefined)
    if(CMAKE_C_COMPILER_ID STREQUAL "GNU")  # (zig's linker has no --exclude-libs; the version
      target_link_options(${target} PRIVATE -Wl,--exclude-libs,ALL)  # script suffices)
    endif()
  endif()
endfunction()

function(csfh_add_fmu_objects target)
  cmake_parse_arguments(ARG "" "" "SOURCES;INCLUDE_DIRS;LINK" ${ARGN})
  add_library(${target} OBJECT ${ARG_SOURCES})
  target_include_directories(${target} PRIVATE ${ARG_INCLUDE_DIRS})
  target_compile_options(${target} PRIVATE ${CSFH_WARNINGS})
  target_link_libraries(${target} PRIVATE ${ARG_LINK})
endfunction()

function(csfh_add_test_importer target)
  cmake_parse_arguments(ARG "" "" "SOURCES;LINK" ${ARGN})
  add_executable(${target} ${ARG_SOURCES})
  set_target_properties(${target} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR})
  target_include_directories(${target} PRIVATE ${FMI_HEADERS_DIR})
  target_compile_options(${target} PRIVATE ${CSFH_WARNINGS})
  target_link_libraries(${target} PRIVATE ${ARG_LINK} ${CMAKE_DL_LIBS})
  if(NOT WIN32)
    target_link_libraries(${target} PRIVATE m)
  endif()
  set_property(GLOBAL APPEND PROPERTY CSFH_TEST_IMPORTERS ${target})
endfunction()

# build/<name>.fmu: modelDescription.xml with <SourceFiles>, binaries/ of every platform built
# (cmake/platforms.cmake), sources/ (the FMU's own sources and headers, the SUNDIALS modules it
# uses and our SUNDIALS configuration: an importer compiles sources/*.c with `-I sources`, and
# whatever its flags the binary exports only the fmi2* functions: csfh_visibility.h),
# documentation/ (index.html from the variables file, SUNDIALS' licence).
#   csfh_add_fmu_package(name MODEL_IDENTIFIER id VARIABLES toml SOURCES .c... HEADERS .h...
#                        SUNDIALS_MODULES m... HOST_TARGET target)
function(csfh_add_fmu_package name)
  cmake_parse_arguments(ARG "" "MODEL_IDENTIFIER;VARIABLES;HOST_TARGET"
                        "SOURCES;HEADERS;SUNDIALS_MODULES" ${ARGN})
  set(id ${ARG_MODEL_IDENTIFIER})
  set(dir ${CMAKE_BINARY_DIR}/generated/package/${name})
  set(fmu ${CMAKE_BINARY_DIR}/${name}.fmu)
  get_filename_component(variables ${ARG_VARIABLES} ABSOLUTE BASE_DIR ${PROJECT_SOURCE_DIR})

  # sources/: flat .c files and private headers, public SUNDIALS headers under their include path
  csfh_sundials_sources(sundials_c MODULES ${ARG_SUNDIALS_MODULES})
  csfh_sundials_headers(sundials_private sundials_public MODULES ${ARG_SUNDIALS_MODULES})
  set(own)
  foreach(f IN LISTS ARG_SOURCES ARG_HEADERS)
    get_filename_component(f ${f} ABSOLUTE BASE_DIR ${PROJECT_SOURCE_DIR})
    list(APPEND own ${f})
  endforeach()
  set(files)
  set(source_names)
  foreach(f IN LISTS own sundials_c sundials_private)
    get_filename_component(n ${f} NAME)
    if(f IN_LIST sundials_private AND EXISTS ${CSFH_SUNDIALS_CONFIG_DIR}/hidden/${n})
      # SUNDIALS' private header that declares internal functions without an export macro: ours
      # (fmu_src/sundials_config/hidden/) takes its place and includes it with them hidden
      list(APPEND files "sources/sundials_private/${n}=${f}")
      set(f ${CSFH_SUNDIALS_CONFIG_DIR}/hidden/${n})
    endif()
    list(APPEND files "sources/${n}=${f}")
    if(n MATCHES "\\.c$")
      list(APPEND source_names ${n})
    endif()
  endforeach()
  foreach(f IN LISTS sundials_public)
    file(RELATIVE_PATH rel ${CSFH_SUNDIALS_SOURCE_DIR}/include ${f})
    list(APPEND files "sources/${rel}=${f}")
  endforeach()
  file(GLOB config_headers ${CSFH_SUNDIALS_CONFIG_DIR}/sundials/*.h)
  foreach(f IN LISTS config_headers)
    get_filename_component(n ${f} NAME)
    list(APPEND files "sources/sundials/${n}=${f}")
  endforeach()
  list(APPEND files
    "documentation/licenses/SUNDIALS-LICENSE.txt=${CSFH_SUNDIALS_SOURCE_DIR}/LICENSE"
    "documentation/licenses/SUNDIALS-NOTICE.txt=${CSFH_SUNDIALS_SOURCE_DIR}/NOTICE"
    "documentation/index.html=${dir}/index.html"
    "modelDescription.xml=${dir}/modelDescription.xml")

  # modelDescription.xml with <SourceFiles> (the same generator, so the same GUID), index.html
  add_custom_command(
    OUTPUT ${dir}/modelDescription.xml ${dir}/index.html
    COMMAND Python3::Interpreter ${PROJECT_SOURCE_DIR}/modelDescription/generate.py
            --version ${PROJECT_VERSION} ${variables} ${dir} --epoch ${CSFH_SOURCE_DATE_EPOCH}
            --source-files ${source_names}
    COMMAND Python3::Interpreter ${PROJECT_SOURCE_DIR}/modelDescription/document.py
            --version ${PROJECT_VERSION} ${variables} ${dir}/index.html
    DEPENDS ${variables} ${CSFH_GENERATOR}
            ${PROJECT_SOURCE_DIR}/python/csfh/_version.py
    COMMENT "Generating the packaged modelDescription.xml and documentation of ${name}.fmu"
    VERBATIM)

  csfh_platform_binaries(binaries ${id} $<TARGET_FILE:${ARG_HOST_TARGET}>)
  set(binary_args)
  set(binary_files)
  foreach(b IN LISTS binaries)
    list(APPEND binary_args --binary "${b}")
    string(REGEX REPLACE "^[^=]*=" "" paths "${b}")
    string(REPLACE "," ";" paths "${paths}")
    list(APPEND binary_files ${paths})
  endforeach()
  set(file_args)
  set(file_deps)
  foreach(f IN LISTS files)
    list(APPEND file_args --file "${f}")
    string(REGEX REPLACE "^[^=]*=" "" path "${f}")
    list(APPEND file_deps ${path})
  endforeach()
  add_custom_command(
    OUTPUT ${fmu}
    COMMAND Python3::Interpreter ${PROJECT_SOURCE_DIR}/tools/fmu_package.py ${fmu}
            ${binary_args} ${file_args}
    DEPENDS ${ARG_HOST_TARGET} ${CSFH_PLATFORM_TARGETS} ${binary_files} ${file_deps}
            ${PROJECT_SOURCE_DIR}/tools/fmu_package.py ${PROJECT_SOURCE_DIR}/tools/macho_fat.py
    COMMENT "Packaging ${name}.fmu (${CSFH_PLATFORMS_BUILT} platforms)"
    VERBATIM)
  add_custom_target(${name}_fmu_package ALL DEPENDS ${fmu})
endfunction()

# build/fmi3/<name>.fmu: the FMI 3.0 build of the same model (the front-end fmu_src/fmu/fmi3/ over
# the same instance, stepper and model), modelDescription.xml from the same variables file
# (generate.py --fmi-version 3), the binaries of every platform built under
# binaries/<platform tuple>/ (FMI 3.0's names; darwin: one directory per architecture) and the
# documentation. A binary FMU: the sources are in the FMI 2.0 FMU.
#   csfh_add_fmu3_package(name MODEL_IDENTIFIER id VARIABLES toml HOST_TARGET target)
function(csfh_add_fmu3_package name)
  cmake_parse_arguments(ARG "" "MODEL_IDENTIFIER;VARIABLES;HOST_TARGET" "" ${ARGN})
  set(id ${ARG_MODEL_IDENTIFIER})
  set(dir ${CMAKE_BINARY_DIR}/generated/package3/${name})
  set(fmu ${CMAKE_BINARY_DIR}/fmi3/${name}.fmu)
  get_filename_component(variables ${ARG_VARIABLES} ABSOLUTE BASE_DIR ${PROJECT_SOURCE_DIR})
  add_custom_command(
    OUTPUT ${dir}/modelDescription.xml ${dir}/index.html
    COMMAND Python3::Interpreter ${PROJECT_SOURCE_DIR}/modelDescription/generate.py
            --version ${PROJECT_VERSION} --fmi-version 3 ${variables} ${dir}
            --epoch ${CSFH_SOURCE_DATE_EPOCH}
    COMMAND Python3::Interpreter ${PROJECT_SOURCE_DIR}/modelDescription/document.py
            --version ${PROJECT_VERSION} ${variables} ${dir}/index.html
    DEPENDS ${variables} ${CSFH_GENERATOR}
            ${PROJECT_SOURCE_DIR}/python/csfh/_version.py
    COMMENT "Generating the FMI 3.0 modelDescription.xml and documentation of fmi3/${name}.fmu"
    VERBATIM)
  csfh_platform_binaries3(binaries ${id} $<TARGET_FILE:${ARG_HOST_TARGET}>)
  set(binary_args)
  set(binary_files)
  foreach(b IN LISTS binaries)
    list(APPEND binary_args --binary "${b}")
    string(REGEX REPLACE "^[^=]*=" "" path "${b}")
    list(APPEND binary_files ${path})
  endforeach()
  add_custom_command(
    OUTPUT ${fmu}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${CMAKE_BINARY_DIR}/fmi3
    COMMAND Python3::Interpreter ${PROJECT_SOURCE_DIR}/tools/fmu_package.py ${fmu}
            ${binary_args}
            --file "modelDescription.xml=${dir}/modelDescription.xml"
            --file "documentation/index.html=${dir}/index.html"
            --file "documentation/licenses/SUNDIALS-LICENSE.txt=${CSFH_SUNDIALS_SOURCE_DIR}/LICENSE"
            --file "documentation/licenses/SUNDIALS-NOTICE.txt=${CSFH_SUNDIALS_SOURCE_DIR}/NOTICE"
    DEPENDS ${ARG_HOST_TARGET} ${CSFH_PLATFORM_TARGETS} ${binary_files}
            ${dir}/modelDescription.xml ${dir}/index.html
            ${PROJECT_SOURCE_DIR}/tools/fmu_package.py
    COMMENT "Packaging fmi3/${name}.fmu (FMI 3.0, ${CSFH_PLATFORMS_BUILT} platforms)"
    VERBATIM)
  add_custom_target(${name}_fmu3_package ALL DEPENDS ${fmu})
endfunction()
