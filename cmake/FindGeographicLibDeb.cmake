# Debian 12 ships GeographicLib without a CMake package config; find it directly.
find_path(GEOGRAPHICLIB_INCLUDE_DIR GeographicLib/LocalCartesian.hpp)
find_library(GEOGRAPHICLIB_LIBRARY NAMES GeographicLib Geographic)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(GeographicLibDeb DEFAULT_MSG GEOGRAPHICLIB_LIBRARY
                                  GEOGRAPHICLIB_INCLUDE_DIR)
if(GeographicLibDeb_FOUND AND NOT TARGET GeographicLib::GeographicLib)
  add_library(GeographicLib::GeographicLib UNKNOWN IMPORTED)
  set_target_properties(GeographicLib::GeographicLib PROPERTIES
    IMPORTED_LOCATION ${GEOGRAPHICLIB_LIBRARY}
    INTERFACE_INCLUDE_DIRECTORIES ${GEOGRAPHICLIB_INCLUDE_DIR})
endif()
