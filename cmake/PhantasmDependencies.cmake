# Every third-party dependency is found here, once; targets link them where they are used.
# scripts/install-deps.sh installs the Debian 12 packages that provide them.
find_package(PkgConfig REQUIRED)
find_package(Threads REQUIRED)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(ZLIB REQUIRED)

# Deformation: sparse Cholesky with an OpenMP OpenBLAS underneath.
find_package(CHOLMOD REQUIRED)
find_package(OpenBLAS CONFIG QUIET)

# Anatomy: CGAL Mesh_3 (header-only; two adapter files include it), with TBB support for its
# faster containers (anatomy/CMakeLists.txt).
find_package(CGAL REQUIRED)
find_package(TBB REQUIRED)
include(CGAL_TBB_support)

# Voxelization and .vdb output.
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED)

# MR acquisition: FFTW (double precision, with its OpenMP threads).
pkg_check_modules(FFTW3 REQUIRED IMPORTED_TARGET fftw3)

# Output formats: NIfTI, HDF5, VTK (mesh I/O and ParaView files, PNG), no ITK.
find_package(Nifti2 MODULE REQUIRED)
# gzip of .nii.gz files: libdeflate, 2-3 times as fast as zlib at the same level (io/nifti_file.cpp).
pkg_check_modules(LIBDEFLATE REQUIRED IMPORTED_TARGET libdeflate)
find_package(HDF5 REQUIRED COMPONENTS C)
find_package(VTK 9 REQUIRED COMPONENTS CommonCore CommonDataModel FiltersCore IOXML IOGeometry IOPLY IOImage)

if(PHANTASM_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(PHANTASM_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
