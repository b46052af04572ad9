# Every dependency comes from a Debian package (scripts/deps.sh installs them).
find_package(Threads REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
# The serial HDF5: PETSc's packages install the MPI build beside it, and
# result files are written by one process.
set(HDF5_PREFER_PARALLEL FALSE)
find_package(HDF5 REQUIRED COMPONENTS C)
find_package(PNG REQUIRED)
find_package(ZLIB REQUIRED)
# NIfTI-1 label volumes: nifti1_io and znzlib. Found by hand: the CMake package
# in Debian 12's libnifti2-dev points at /usr/lib/libznz.so.3.0.0, which the
# package installs under the multiarch directory instead.
find_path(NIFTI_INCLUDE_DIR nifti1_io.h PATH_SUFFIXES nifti REQUIRED)
find_library(NIFTIIO_LIBRARY niftiio REQUIRED)
find_library(ZNZ_LIBRARY znz REQUIRED)
add_library(pba_nifti INTERFACE)
target_include_directories(pba_nifti INTERFACE ${NIFTI_INCLUDE_DIR})
target_link_libraries(pba_nifti INTERFACE ${NIFTIIO_LIBRARY} ${ZNZ_LIBRARY} ZLIB::ZLIB m)
find_package(Protobuf REQUIRED)
find_package(gRPC CONFIG REQUIRED)
find_package(SQLite3 REQUIRED)
find_package(yaml-cpp REQUIRED)
find_package(tinyxml2 CONFIG REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(spdlog CONFIG REQUIRED)
find_package(OpenMP REQUIRED COMPONENTS CXX)
find_package(OpenSSL REQUIRED COMPONENTS Crypto)
# Header-only CGAL 5.5 (Mesh_3 for the atlas's labelled meshes), with GMP,
# MPFR and Boost headers.
find_package(CGAL 5.5 REQUIRED)

# SuiteSparse (CHOLMOD) ships no CMake package in Debian 12: find it by hand.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig REQUIRED)
add_library(pba_cholmod INTERFACE)
target_include_directories(pba_cholmod INTERFACE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(pba_cholmod INTERFACE ${CHOLMOD_LIBRARY} ${SUITESPARSE_CONFIG_LIBRARY})

# PETSc 3.18 (libpetsc-real-dev: hypre, MUMPS, GAMG) and the MPI it is
# built on (Open MPI): the scalable linear solvers, and runs on several
# ranks. Debian's PETSc ships a pkg-config file only.
find_package(MPI REQUIRED COMPONENTS C)
find_package(PkgConfig REQUIRED)
pkg_check_modules(PETSC REQUIRED IMPORTED_TARGET PETSc>=3.18)
add_library(pba_petsc INTERFACE)
target_link_libraries(pba_petsc INTERFACE PkgConfig::PETSC MPI::MPI_C)
# MPI's C API only: Open MPI's deprecated C++ bindings would need libmpi_cxx.
target_compile_definitions(pba_petsc INTERFACE OMPI_SKIP_MPICXX=1 MPICH_SKIP_MPICXX=1)

find_program(GRPC_CPP_PLUGIN grpc_cpp_plugin REQUIRED)
# What tests that start mpirun give it: Open MPI refuses to run as root
# unless told (CI runs as root), and a test machine may have fewer cores
# than the ranks a test starts.
set(PBA_MPIRUN_ENVIRONMENT
  "OMPI_ALLOW_RUN_AS_ROOT=1;OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1;OMPI_MCA_rmaps_base_oversubscribe=1")
