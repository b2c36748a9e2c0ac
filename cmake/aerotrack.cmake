# Project-wide compiler settings and the helper that declares one library per module/backend.

add_library(aerotrack_warnings INTERFACE)
target_compile_options(aerotrack_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor -Wold-style-cast -Wcast-align
  -Wunused -Woverloaded-virtual -Wnull-dereference -Wdouble-promotion -Wformat=2
  -Wimplicit-fallthrough)
# GCC 12 reports a false -Wrestrict inside libstdc++'s std::string operator+ at -O2 (GCC bug
# 105651, fixed in GCC 13); it is not about our code.
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
  target_compile_options(aerotrack_warnings INTERFACE -Wno-restrict)
endif()
if(AEROTRACK_WERROR)
  target_compile_options(aerotrack_warnings INTERFACE -Werror)
endif()

if(AEROTRACK_SANITIZE)
  message(STATUS "aerotrack: building with -fsanitize=${AEROTRACK_SANITIZE}")
  add_compile_options(-fsanitize=${AEROTRACK_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${AEROTRACK_SANITIZE})
endif()

# aerotrack_library(<name> [DIR <subdir>] [SOURCES <files...>] [PUBLIC_DEPS <targets...>]
#                   [PRIVATE_DEPS <targets...>])
# Declares target aerotrack_<name> (alias aerotrack::<name>) whose public headers are in
# <subdir>/include and whose SOURCES are relative to <subdir> (default: the current folder).
# Without SOURCES the library is header-only (INTERFACE).
function(aerotrack_library name)
  cmake_parse_arguments(ARG "" "DIR" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  set(target aerotrack_${name})
  set(root ${CMAKE_CURRENT_SOURCE_DIR})
  if(ARG_DIR)
    set(root ${CMAKE_CURRENT_SOURCE_DIR}/${ARG_DIR})
  endif()
  if(ARG_SOURCES)
    list(TRANSFORM ARG_SOURCES PREPEND ${root}/)
    add_library(${target} STATIC ${ARG_SOURCES})
    target_include_directories(${target} PUBLIC ${root}/include)
    target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS} aerotrack_warnings)
  else()
    add_library(${target} INTERFACE)
    target_include_directories(${target} INTERFACE ${root}/include)
    target_link_libraries(${target} INTERFACE ${ARG_PUBLIC_DEPS})
  endif()
  add_library(aerotrack::${name} ALIAS ${target})
endfunction()
