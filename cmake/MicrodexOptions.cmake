# Compiler options shared by every microdex target.
option(MICRODEX_WERROR "Treat warnings as errors" OFF)
set(MICRODEX_SANITIZE "" CACHE STRING "Sanitizers: '', 'address,undefined' or 'thread'")

# microdex_warnings: an interface target every first-party target links to.
add_library(microdex_warnings INTERFACE)
target_compile_options(microdex_warnings INTERFACE
  -Wall -Wextra -Wpedantic $<$<CXX_COMPILER_ID:GNU>:-Wshadow=local> -Wnon-virtual-dtor
  -Wno-missing-field-initializers
  $<$<BOOL:${MICRODEX_WERROR}>:-Werror>)

# Floating-point contraction is pinned so that a replay re-simulates bit for bit
# whatever the compiler decides about fused multiply-adds.
add_compile_options(-ffp-contract=off)

if(MICRODEX_SANITIZE)
  add_compile_options(-fsanitize=${MICRODEX_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${MICRODEX_SANITIZE})
endif()

if(NOT CMAKE_BUILD_TYPE AND NOT CMAKE_CONFIGURATION_TYPES)
  set(CMAKE_BUILD_TYPE Release CACHE STRING "" FORCE)
endif()
