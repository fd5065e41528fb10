# One place that configures every octolod target: language level, warnings, sanitizers.
include_guard(GLOBAL)

option(OCTOLOD_WERROR "Treat compiler warnings as errors" OFF)
option(OCTOLOD_SANITIZE "Build with AddressSanitizer + UndefinedBehaviorSanitizer" OFF)

option(OCTOLOD_SANITIZE_THREAD "Build with ThreadSanitizer (not with OCTOLOD_SANITIZE)" OFF)

if(OCTOLOD_SANITIZE AND OCTOLOD_SANITIZE_THREAD)
  message(FATAL_ERROR "OCTOLOD_SANITIZE and OCTOLOD_SANITIZE_THREAD cannot be combined")
endif()
if(OCTOLOD_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()
if(OCTOLOD_SANITIZE_THREAD)
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
endif()

function(octolod_configure_target target)
  target_compile_features(${target} PUBLIC cxx_std_20)
  set_target_properties(${target} PROPERTIES CXX_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wshadow -Wconversion)
  if(OCTOLOD_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  # GCC 12 at -O3 reports -Wrestrict inside libstdc++ for `"literal" + std::string` (GCC bug
  # 105329, fixed in 13): a false positive in the standard library, not in our code.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
endfunction()

# octolod_optimize_when_sanitized(<target>): the sanitized build (CMAKE_BUILD_TYPE Debug) compiles
# <target> at -O1, as AddressSanitizer's documentation recommends for reasonable speed. For the
# libraries that do per-triangle work (baking, measuring, generating samples): at -O0 their tests
# took 431 s of the sanitized suite, at -O1 227 s. Everything else stays at -O0 (it would cost more
# build time than its tests gain).
function(octolod_optimize_when_sanitized target)
  if(OCTOLOD_SANITIZE)
    target_compile_options(${target} PRIVATE -O1)
  endif()
endfunction()

# octolod_add_library(<name> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates octolod_<name> with alias octolod::<name>, public headers in <dir>/include.
function(octolod_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(octolod_${name} ${ARG_SOURCES})
  add_library(octolod::${name} ALIAS octolod_${name})
  set_target_properties(octolod_${name} PROPERTIES EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  target_include_directories(octolod_${name}
    PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>
    PRIVATE ${CMAKE_CURRENT_SOURCE_DIR}/src)
  target_link_libraries(octolod_${name} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  octolod_configure_target(octolod_${name})
endfunction()
