# The optional peer linear solvers of LinearSolverFactory.cxx. Each is on by
# default and built when its library is found; when it is missing, configure
# says so and the solver is simply not in GetLinearSolverNames().

option(TRANSLUCENCY_USE_CHOLMOD "Build the 'cholmod' linear solver (SuiteSparse CHOLMOD)" ON)
set(TRANSLUCENCY_HAVE_CHOLMOD OFF CACHE INTERNAL "")
if (TRANSLUCENCY_USE_CHOLMOD)
  find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
  find_library(CHOLMOD_LIBRARY NAMES cholmod)
  if (CHOLMOD_INCLUDE_DIR AND CHOLMOD_LIBRARY)
    message(STATUS "Linear solver 'cholmod': ${CHOLMOD_LIBRARY}")
    target_sources(TranslucencyLinearAlgebra PRIVATE CholmodSolver.cxx)
    target_include_directories(TranslucencyLinearAlgebra PRIVATE "${CHOLMOD_INCLUDE_DIR}")
    target_link_libraries(TranslucencyLinearAlgebra PRIVATE "${CHOLMOD_LIBRARY}")
    target_compile_definitions(TranslucencyLinearAlgebra PRIVATE TRANSLUCENCY_HAVE_CHOLMOD)
    set(TRANSLUCENCY_HAVE_CHOLMOD ON CACHE INTERNAL "")
    # CHOLMOD's supernodal factorisation runs in BLAS: the reference BLAS is
    # ~10x slower than OpenBLAS (Debian libopenblas0-pthread).
    # CHOLMOD links libblas.so.3, which Debian's alternatives point at
    # OpenBLAS once libopenblas0-pthread is installed.
    find_library(TRANSLUCENCY_BLAS_LIBRARY NAMES libblas.so.3 blas)
    if (TRANSLUCENCY_BLAS_LIBRARY)
      get_filename_component(blas_real "${TRANSLUCENCY_BLAS_LIBRARY}" REALPATH)
    endif ()
    if (blas_real MATCHES "openblas")
      message(STATUS "Linear solver 'cholmod': BLAS is OpenBLAS (${blas_real})")
    else ()
      message(STATUS "Linear solver 'cholmod': the BLAS is '${blas_real}', not OpenBLAS: "
        "CHOLMOD will be ~10x slower (install libopenblas0-pthread)")
    endif ()
  else ()
    message(STATUS "Linear solver 'cholmod' NOT built: cholmod.h / libcholmod not found "
      "(Debian: apt-get install libsuitesparse-dev libopenblas0-pthread; "
      "or -DTRANSLUCENCY_USE_CHOLMOD=OFF to silence this)")
  endif ()
else ()
  message(STATUS "Linear solver 'cholmod' disabled (TRANSLUCENCY_USE_CHOLMOD=OFF)")
endif ()

option(TRANSLUCENCY_USE_HYPRE "Build the 'hypre-amg' linear solver (hypre BoomerAMG-PCG)" ON)
set(TRANSLUCENCY_HAVE_HYPRE OFF CACHE INTERNAL "")
if (TRANSLUCENCY_USE_HYPRE)
  find_path(HYPRE_INCLUDE_DIR HYPRE.h PATH_SUFFIXES hypre)
  find_library(HYPRE_LIBRARY NAMES HYPRE)
  find_package(MPI QUIET COMPONENTS C)
  if (HYPRE_INCLUDE_DIR AND HYPRE_LIBRARY AND MPI_C_FOUND)
    message(STATUS "Linear solver 'hypre-amg': ${HYPRE_LIBRARY} (MPI ${MPI_C_VERSION})")
    # SchwarzAggregation.cxx: the distributed variant of multigrid-agg
    # (hypre's ParCSR PCG with an additive Schwarz aggregation cycle);
    # HypreParCSR.cxx: what it shares with HypreSolver.cxx; DistributedPCG.cxx:
    # their three-channel PCG (SolveChannels).
    target_sources(TranslucencyLinearAlgebra PRIVATE HypreSolver.cxx HypreParCSR.cxx DistributedPCG.cxx
      SchwarzAggregation.cxx)
    target_include_directories(TranslucencyLinearAlgebra PUBLIC
      $<BUILD_INTERFACE:${HYPRE_INCLUDE_DIR}>)
    target_link_libraries(TranslucencyLinearAlgebra PUBLIC "${HYPRE_LIBRARY}" MPI::MPI_C)
    # Open MPI's mpi.h pulls in its C++ bindings (libmpi_cxx) in C++ files.
    target_compile_definitions(TranslucencyLinearAlgebra PUBLIC OMPI_SKIP_MPICXX MPICH_SKIP_MPICXX)
    target_compile_definitions(TranslucencyLinearAlgebra PRIVATE TRANSLUCENCY_HAVE_HYPRE)
    set(TRANSLUCENCY_HAVE_HYPRE ON CACHE INTERNAL "")
  else ()
    message(STATUS "Linear solver 'hypre-amg' NOT built: HYPRE.h / libHYPRE / MPI not found "
      "(Debian: apt-get install libhypre-dev; or -DTRANSLUCENCY_USE_HYPRE=OFF to silence this)")
  endif ()
else ()
  message(STATUS "Linear solver 'hypre-amg' disabled (TRANSLUCENCY_USE_HYPRE=OFF)")
endif ()
