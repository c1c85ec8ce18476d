# The library's sources and how they compile, shared by native/CMakeLists.txt and the add-on
# library's own build (native/addon_library, configured with zig's clang).
set(NDFBAKE_NATIVE_DIR ${CMAKE_CURRENT_LIST_DIR}/..)
cmake_path(NORMAL_PATH NDFBAKE_NATIVE_DIR)
file(GLOB_RECURSE NDFBAKE_SOURCES CONFIGURE_DEPENDS ${NDFBAKE_NATIVE_DIR}/src/*.cpp)
# What reads or writes image files through OpenImageIO; the add-on's library has
# src/io/no_image_files.cpp in their place, which refuses.
set(NDFBAKE_IMAGE_FILE_SOURCES
  ${NDFBAKE_NATIVE_DIR}/src/io/color_decode.cpp
  ${NDFBAKE_NATIVE_DIR}/src/io/image_files.cpp
  ${NDFBAKE_NATIVE_DIR}/src/io/image_read.cpp
  ${NDFBAKE_NATIVE_DIR}/src/io/normal_encode.cpp
  ${NDFBAKE_NATIVE_DIR}/src/io/normal_file_decode.cpp)
set(NDFBAKE_NO_IMAGE_FILE_SOURCES ${NDFBAKE_NATIVE_DIR}/src/io/no_image_files.cpp)
list(REMOVE_ITEM NDFBAKE_SOURCES ${NDFBAKE_IMAGE_FILE_SOURCES} ${NDFBAKE_NO_IMAGE_FILE_SOURCES})
# Research code: the benchmark, the baseline representations it compares (baselines/: the bake's
# report computes its single-vMF and Toksvig figures with ndf/moments) and the ground-truth entry
# points of ndfbake_research.h. The full library carries it; the add-on's library is built from
# NDFBAKE_SOURCES alone.
file(GLOB NDFBAKE_RESEARCH_SOURCES CONFIGURE_DEPENDS ${NDFBAKE_NATIVE_DIR}/src/bench/*.cpp
     ${NDFBAKE_NATIVE_DIR}/src/baselines/*.cpp)
list(APPEND NDFBAKE_RESEARCH_SOURCES ${NDFBAKE_NATIVE_DIR}/src/capi/research_exports.cpp)
list(REMOVE_ITEM NDFBAKE_SOURCES ${NDFBAKE_RESEARCH_SOURCES})

# -fopenmp-simd honours `#pragma omp simd` (vectorized reductions in the EM E-step) without
# OpenMP threads or -ffast-math. -fno-trapping-math lets GCC turn the float comparisons inside
# those loops (fast_exp's clamp, max over lobes) into selects: with the default, a comparison may
# raise an FP exception, so GCC keeps the branch and leaves the loop scalar. Nothing here enables
# FP traps, and no result changes: only where the exceptions would be raised.
function(ndfbake_object_library name)
  add_library(${name} OBJECT ${ARGN})
  target_include_directories(${name}
    PUBLIC ${NDFBAKE_NATIVE_DIR}/include ${NDFBAKE_NATIVE_DIR}/src)
  target_compile_options(${name} PRIVATE -Wall -Wextra -Wpedantic -fopenmp-simd -fno-trapping-math)
  target_compile_definitions(${name}
    PUBLIC NDFBAKE_VERSION_STRING="${PROJECT_VERSION}" PRIVATE NDFBAKE_BUILDING)
endfunction()
