# What `cmake --install <build> [--prefix P]` installs, and the CMake package that lets another
# project use it:
#   P/lib/libseiche_{neighbor,kernels,core,export}.so  the layers: shared in a build with OpenVDB
#                                                        (Debian's FindOpenVDB sets BUILD_SHARED_LIBS),
#                                                        static (.a, position-independent) without
#   P/include/seiche/...                                 the public headers: seiche/seiche.hpp (the
#                                                        umbrella, docs/api.md) and what it includes
#   P/lib/cmake/Seiche/SeicheConfig.cmake, SeicheConfigVersion.cmake, SeicheTargets.cmake
#   P/bin/seiche                                         the command line
#   P/<SEICHE_PYTHON_INSTALL_DIR>/seiche/                the Python package (python/CMakeLists.txt)
# A consumer: find_package(Seiche 0.2 REQUIRED) and target_link_libraries(app PRIVATE
# Seiche::seiche); Seiche::core, ::kernels, ::neighbor and ::export are the layers one by one.
# The SIMD layer (simd/) is header-only and private to the kernels: it is not installed.
# RPATH: CMake strips the build tree's at install; what is installed finds the shared layers
# relative to itself ($ORIGIN), so the prefix can be moved: the layers each other in lib/, the
# CLI ../lib, the Python module (python/CMakeLists.txt) its way up from site-packages.
include(CMakePackageConfigHelpers)

# Seiche::seiche: everything, for `target_link_libraries(app Seiche::seiche)`. (The target `seiche`
# is the command line, hence the internal name.)
add_library(seiche_library INTERFACE)
target_link_libraries(seiche_library INTERFACE seiche_core seiche_export)
set_target_properties(seiche_library PROPERTIES EXPORT_NAME seiche)
add_library(Seiche::seiche ALIAS seiche_library)
foreach(layer neighbor kernels core export)
  set_target_properties(seiche_${layer} PROPERTIES EXPORT_NAME ${layer} INSTALL_RPATH "$ORIGIN")
endforeach()
file(RELATIVE_PATH seiche_bin_to_lib ${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_BINDIR} ${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR})
set_target_properties(seiche PROPERTIES INSTALL_RPATH "$ORIGIN/${seiche_bin_to_lib}")

install(TARGETS seiche_neighbor seiche_kernels seiche_core seiche_export seiche_library
        EXPORT SeicheTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS seiche RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

install(DIRECTORY ${PROJECT_SOURCE_DIR}/core/include/ ${PROJECT_SOURCE_DIR}/kernels/include/
                  ${PROJECT_SOURCE_DIR}/neighbor/include/
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")
install(FILES ${PROJECT_SOURCE_DIR}/core/export/include/seiche/export/scene_exporters.hpp
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/seiche/export)
if(SEICHE_WITH_OPENVDB)
  install(FILES ${PROJECT_SOURCE_DIR}/core/export/include/seiche/export/vdb_exporter.hpp
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/seiche/export)
endif()

set(SEICHE_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/Seiche)
install(EXPORT SeicheTargets NAMESPACE Seiche:: DESTINATION ${SEICHE_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/SeicheConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/SeicheConfig.cmake INSTALL_DESTINATION ${SEICHE_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/SeicheConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/SeicheConfig.cmake ${PROJECT_BINARY_DIR}/SeicheConfigVersion.cmake
        DESTINATION ${SEICHE_CMAKE_DIR})
