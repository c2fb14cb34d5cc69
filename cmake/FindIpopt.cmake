# Finds Debian's coinor-libipopt-dev through pkg-config and exposes Ipopt::Ipopt.
find_package(PkgConfig REQUIRED)
pkg_check_modules(IPOPT_PC REQUIRED IMPORTED_TARGET ipopt)
if(NOT TARGET Ipopt::Ipopt)
  add_library(Ipopt::Ipopt INTERFACE IMPORTED)
  target_link_libraries(Ipopt::Ipopt INTERFACE PkgConfig::IPOPT_PC)
endif()
set(Ipopt_FOUND TRUE)
