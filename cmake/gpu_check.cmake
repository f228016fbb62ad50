# Initial cache of the GPU check's build (`make gpu-check-build`, -C this file):
# programs that start on a CUDA machine with none of this machine's libraries.
#   - the C++ runtime, libgcc and libgomp linked statically, cudart_static
#     (it opens the driver's libcuda.so.1 at run time), and every library
#     found as a static archive (KEYMESH_GPU_CHECK prefers .a);
#   - no module opened at run time (GDCM, MPI), no Python module, and no
#     blosc (Debian's static libblosc needs lz4/zstd archives it does not ship);
#   - sm_90 machine code plus compute_90 PTX (H100 / H200; newer GPUs JIT the PTX).
# docs/gpu-check.md says how the programs are checked and run.
set(CMAKE_BUILD_TYPE Release CACHE STRING "")
set(CMAKE_CUDA_ARCHITECTURES 90 CACHE STRING "")
# The fatbinaries compressed for size: with every generator on the device the
# three programs passed the 40 MB the issue allows (43.1 MB, 2026-11-29).
set(CMAKE_CUDA_FLAGS "--compress-mode=size" CACHE STRING "")
set(KEYMESH_GPU_CHECK ON CACHE BOOL "")
set(KEYMESH_CUDA ON CACHE BOOL "")
set(KEYMESH_GDCM OFF CACHE BOOL "")
set(KEYMESH_BLOSC OFF CACHE BOOL "")
set(KEYMESH_MPI OFF CACHE BOOL "")
set(KEYMESH_PYTHON OFF CACHE BOOL "")
set(KEYMESH_BUILD_TESTS OFF CACHE BOOL "")
set(KEYMESH_BUILD_BENCH OFF CACHE BOOL "")
set(ZLIB_USE_STATIC_LIBS ON CACHE BOOL "")
set(CMAKE_EXE_LINKER_FLAGS "-static-libstdc++ -static-libgcc" CACHE STRING "")
