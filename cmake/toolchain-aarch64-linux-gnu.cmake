# CMake toolchain file: cross-compile for 64-bit ARM Linux (aarch64, Debian arm64) with
# Debian's cross compilers (packages g++-aarch64-linux-gnu, gcc-aarch64-linux-gnu).
#
# Where the arm64 libraries come from (docs/deployment.md, "Cross-building for aarch64"):
#   - a sysroot (recommended on a development machine): a folder holding the arm64 -dev
#     packages unpacked, made by scripts/cross_build_arm64.sh. Pass it as
#       -DVP_ARM64_SYSROOT=/path/to/sysroot   (or the environment variable VP_ARM64_SYSROOT)
#   - Debian multiarch (no sysroot given): the arm64 -dev packages installed on the build
#     machine itself (dpkg --add-architecture arm64; apt-get install libopencv-dev:arm64 ...).
#     On Debian 12 this only works on a machine WITHOUT the amd64 -dev packages of OpenCV,
#     yaml-cpp, GeographicLib, XNNPACK and pthreadpool: those are not "Multi-Arch: same",
#     so apt removes the amd64 ones to install the arm64 ones (a dedicated build container).
#
# Tests run under QEMU user emulation when qemu-user-static (or qemu-user) is installed:
# CMAKE_CROSSCOMPILING_EMULATOR is set, so gtest_discover_tests and ctest use it.
#
# Usage:
#   cmake -S . -B build-arm64 -G Ninja -DCMAKE_BUILD_TYPE=Release \
#         -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-aarch64-linux-gnu.cmake \
#         -DVP_ARM64_SYSROOT=/work/pkgwork/sysroot-arm64

set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

set(VP_CROSS_TRIPLE aarch64-linux-gnu)
find_program(VP_CROSS_CXX ${VP_CROSS_TRIPLE}-g++)
find_program(VP_CROSS_CC ${VP_CROSS_TRIPLE}-gcc)
if(NOT VP_CROSS_CXX OR NOT VP_CROSS_CC)
  message(FATAL_ERROR "toolchain-aarch64-linux-gnu.cmake: ${VP_CROSS_TRIPLE}-g++ / -gcc not found "
                      "in PATH; install them with: apt-get install g++-aarch64-linux-gnu")
endif()
set(CMAKE_C_COMPILER ${VP_CROSS_CC})
set(CMAKE_CXX_COMPILER ${VP_CROSS_CXX})

# The sysroot: a cache variable first, then the environment (try_compile projects re-read
# this file and see only the environment and the forwarded variable below).
if(NOT VP_ARM64_SYSROOT AND DEFINED ENV{VP_ARM64_SYSROOT})
  set(VP_ARM64_SYSROOT "$ENV{VP_ARM64_SYSROOT}")
endif()
set(VP_ARM64_SYSROOT "${VP_ARM64_SYSROOT}" CACHE PATH
    "arm64 sysroot (unpacked Debian arm64 packages); empty = Debian multiarch on this machine")
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES VP_ARM64_SYSROOT)

if(VP_ARM64_SYSROOT)
  if(NOT EXISTS "${VP_ARM64_SYSROOT}/usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}")
    message(FATAL_ERROR "toolchain-aarch64-linux-gnu.cmake: VP_ARM64_SYSROOT=${VP_ARM64_SYSROOT} "
                        "has no usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}; make it with "
                        "scripts/cross_build_arm64.sh --sysroot-only")
  endif()
  set(CMAKE_SYSROOT "${VP_ARM64_SYSROOT}")
  set(CMAKE_FIND_ROOT_PATH "${VP_ARM64_SYSROOT}")
  # Libraries, headers and CMake packages only from the sysroot; programs (idlc, protoc)
  # from the build machine.
  set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
  set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
  set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
  set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
  set(VP_QEMU_PREFIX "${VP_ARM64_SYSROOT}")
else()
  # Multiarch: arm64 libraries live beside the build machine's in /usr/lib/aarch64-linux-gnu;
  # CMAKE_LIBRARY_ARCHITECTURE makes find_library / find_package look there first.
  set(VP_QEMU_PREFIX "/")
endif()

find_program(VP_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(VP_QEMU_AARCH64)
  # -L: where the arm64 dynamic loader and libraries are.
  set(CMAKE_CROSSCOMPILING_EMULATOR "${VP_QEMU_AARCH64};-L;${VP_QEMU_PREFIX}")
endif()
