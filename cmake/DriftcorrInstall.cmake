# Installs the libraries, their public headers, the CLI (BUILD_EXAMPLES) and the CMake package
# driftcorr (lib/cmake/driftcorr): find_package(driftcorr) gives driftcorr::core, ::mapping,
# ::surface_io, ::optim, ::io, ::pipeline and ::eval.
include(CMakePackageConfigHelpers)

set(DRIFTCORR_LIBRARIES driftcorr_core driftcorr_mapping driftcorr_surface_io driftcorr_optim
    driftcorr_io driftcorr_pipeline driftcorr_eval)
foreach(lib ${DRIFTCORR_LIBRARIES})
  string(REPLACE "driftcorr_" "" export_name ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${export_name}
    VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
endforeach()

install(TARGETS ${DRIFTCORR_LIBRARIES} EXPORT driftcorrTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
foreach(dir core mapping mapping/surface_io optim examples/io examples/pipeline examples/eval)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
    FILES_MATCHING PATTERN "*.h")
endforeach()
if(TARGET driftcorr)
  install(TARGETS driftcorr RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

set(DRIFTCORR_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/driftcorr)
install(EXPORT driftcorrTargets NAMESPACE driftcorr:: FILE driftcorrTargets.cmake
  DESTINATION ${DRIFTCORR_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/driftcorrConfig.cmake.in
  ${PROJECT_BINARY_DIR}/driftcorrConfig.cmake INSTALL_DESTINATION ${DRIFTCORR_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/driftcorrConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
# The find modules go along: a static build's link interface names Ipopt::Ipopt and
# GeographicLib::GeographicLib, which only these modules define on Debian.
install(FILES ${PROJECT_BINARY_DIR}/driftcorrConfig.cmake
  ${PROJECT_BINARY_DIR}/driftcorrConfigVersion.cmake
  ${PROJECT_SOURCE_DIR}/cmake/FindIpopt.cmake ${PROJECT_SOURCE_DIR}/cmake/FindGeographicLibDeb.cmake
  DESTINATION ${DRIFTCORR_CMAKE_DIR})
