# Cross-compiling for 64-bit ARM with Debian's cross compiler (package g++-aarch64-linux-gnu), for
# the AArch64 compile check of the SIMD layer (xsimd's NEON path; scripts/check-widths.sh):
#   cmake -S . -B build/widths/aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/aarch64-linux-gnu.cmake \
#         -DSEICHE_MARCH=armv8-a -DSEICHE_BUILD_TESTS=OFF -DSEICHE_BUILD_BENCHMARKS=OFF \
#         -DSEICHE_WITH_OPENVDB=OFF
# Compile only. The packages found are the host's: what the kernels and the neighbor search use
# of them (xsimd, xtl, TBB) is headers, which Debian installs under /usr/include for every
# architecture alike; their x86-64 libraries are never linked (the two targets are static
# libraries). Nothing here builds a program that runs on ARM.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# Headers: the cross compiler's own directories first (libstdc++ and glibc for AArch64, under
# /usr/aarch64-linux-gnu/include), then the host's /usr/include for the architecture-independent
# ones. Debian's cross g++ 12 already searches /usr/include last; -idirafter keeps it so for one
# that does not, and never places it before the cross glibc (unlike -I or -isystem).
set(CMAKE_CXX_FLAGS_INIT "-idirafter /usr/include")

# Libraries and headers are looked up in the cross root only; packages (CMake config files) on
# the host, including its architecture's folder, where Debian puts TBB's, xsimd's and fmt's.
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE NEVER)
list(APPEND CMAKE_PREFIX_PATH /usr/lib/${CMAKE_HOST_SYSTEM_PROCESSOR}-linux-gnu/cmake)
