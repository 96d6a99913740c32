# Debian's OpenSubdiv config names a static libosdCPU.a that is not installed, so
# find_package(OpenSubdiv CONFIG) fails: find the headers and the shared library by hand.
find_path(OpenSubdiv_INCLUDE_DIR opensubdiv/far/topologyRefiner.h)
find_library(OpenSubdiv_CPU_LIBRARY osdCPU)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenSubdiv REQUIRED_VARS OpenSubdiv_CPU_LIBRARY OpenSubdiv_INCLUDE_DIR)
if(OpenSubdiv_FOUND AND NOT TARGET OpenSubdiv::osdCPU)
  add_library(OpenSubdiv::osdCPU SHARED IMPORTED)
  set_target_properties(OpenSubdiv::osdCPU PROPERTIES
    IMPORTED_LOCATION "${OpenSubdiv_CPU_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OpenSubdiv_INCLUDE_DIR}")
endif()
mark_as_advanced(OpenSubdiv_INCLUDE_DIR OpenSubdiv_CPU_LIBRARY)
