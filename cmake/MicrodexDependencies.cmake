# Every third-party dependency, found once. deploy/install-deps installs them all.
find_package(Threads REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(fastcdr REQUIRED)
find_package(fastrtps REQUIRED)
find_package(fcl REQUIRED)
find_package(assimp REQUIRED)
find_package(yaml-cpp REQUIRED)
find_package(spdlog REQUIRED)
find_package(CLI11 REQUIRED)
find_package(GTest REQUIRED)
find_package(benchmark REQUIRED)
find_package(SQLite3 REQUIRED)
# Boost.Beast (the view pages' HTTP + WebSocket server): header-only.
find_package(Boost 1.74 REQUIRED)
# node + npm bundle the view pages (common/view/CMakeLists.txt).
find_program(NODE_EXECUTABLE node REQUIRED)
find_program(NPM_EXECUTABLE npm REQUIRED)

# SuiteSparse 5 ships no CMake config: CHOLMOD is found by hand.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(SUITESPARSECONFIG_LIBRARY suitesparseconfig REQUIRED)
add_library(microdex::cholmod INTERFACE IMPORTED)
target_include_directories(microdex::cholmod INTERFACE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(microdex::cholmod INTERFACE ${CHOLMOD_LIBRARY} ${SUITESPARSECONFIG_LIBRARY})

find_program(FASTDDSGEN_EXECUTABLE fastddsgen REQUIRED)

# xxHash (XXH3) for the station state hash; Debian's libxxhash-dev ships no CMake config.
find_path(XXHASH_INCLUDE_DIR xxhash.h REQUIRED)
find_library(XXHASH_LIBRARY xxhash REQUIRED)
add_library(microdex::xxhash INTERFACE IMPORTED)
target_include_directories(microdex::xxhash INTERFACE ${XXHASH_INCLUDE_DIR})
target_link_libraries(microdex::xxhash INTERFACE ${XXHASH_LIBRARY})

# OpenSSL: DDS Security files checked before use (common/net), the console's HTTPS.
find_package(OpenSSL 3 REQUIRED)
# libsodium: the console's password hashes (Argon2id); Debian's libsodium-dev ships no CMake
# config.
find_path(SODIUM_INCLUDE_DIR sodium.h REQUIRED)
find_library(SODIUM_LIBRARY sodium REQUIRED)
add_library(microdex::sodium INTERFACE IMPORTED)
target_include_directories(microdex::sodium INTERFACE ${SODIUM_INCLUDE_DIR})
target_link_libraries(microdex::sodium INTERFACE ${SODIUM_LIBRARY})
