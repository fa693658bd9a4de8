# Installation: static libraries, public headers (include/vecat/<folder>/<name>.hpp, so the project's
# `#include "cia402/drive.hpp"` works with include/vecat on the include path), the vecat program, a CMake
# package (find_package(vecat) gives vecat::testing, vecat::master, ...), a pkg-config file, and a Debian
# package through CPack (cpack -G DEB in the build directory).
include(CMakePackageConfigHelpers)

set(VECAT_INSTALL_LIBS vecat_common vecat_protocol vecat_device vecat_esc vecat_coe vecat_twinsync_parameters vecat_twinsync vecat_motion vecat_drive_core vecat_cia402
                       vecat_net vecat_serve vecat_report vecat_faults vecat_io vecat_master vecat_telemetry vecat_testing vecat_esi vecat_soe vecat_network)
if(VECAT_TELEMETRY)
  list(APPEND VECAT_INSTALL_LIBS vecat_telemetry_idl)
endif()
# Exported as vecat::<name without the vecat_ prefix>, the same names as the aliases in the build.
foreach(lib IN LISTS VECAT_INSTALL_LIBS)
  string(REGEX REPLACE "^vecat_" "" short ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${short})
endforeach()
# The warning flags are private to the build; static libraries still name them in their link interface.
set_target_properties(vecat_warnings PROPERTIES EXPORT_NAME warnings)

install(TARGETS ${VECAT_INSTALL_LIBS} vecat_warnings
        EXPORT vecatTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vecat)
install(TARGETS vecat RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vecat
        FILES_MATCHING PATTERN "*.hpp" PATTERN "cli" EXCLUDE)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/esi/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/vecat/esi
        FILES_MATCHING PATTERN "*.hpp")

set(VECAT_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/vecat)
install(EXPORT vecatTargets NAMESPACE vecat:: DESTINATION ${VECAT_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/vecatConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/vecatConfig.cmake INSTALL_DESTINATION ${VECAT_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vecatConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/vecatConfig.cmake ${PROJECT_BINARY_DIR}/vecatConfigVersion.cmake
        DESTINATION ${VECAT_CMAKE_DIR})

# pkg-config: all libraries, users first (static linking resolves left to right).
set(VECAT_PC_LIBS "-lvecat_network -lvecat_testing -lvecat_esi -lvecat_master -lvecat_telemetry -lvecat_io -lvecat_faults")
if(VECAT_TELEMETRY)
  string(APPEND VECAT_PC_LIBS " -lvecat_telemetry_idl")
  set(VECAT_PC_REQUIRES "fmt yaml-cpp pugixml libcap CycloneDDS")
else()
  set(VECAT_PC_REQUIRES "fmt yaml-cpp pugixml libcap")
endif()
string(APPEND VECAT_PC_LIBS " -lvecat_soe -lvecat_report -lvecat_cia402 -lvecat_drive_core -lvecat_motion -lvecat_twinsync -lvecat_coe -lvecat_serve -lvecat_net -lvecat_esc"
                            " -lvecat_device -lvecat_protocol -pthread")
# The prefix relative to the .pc file, so that the file is right wherever the tree is installed (--prefix).
file(RELATIVE_PATH VECAT_PC_TO_PREFIX /root/${CMAKE_INSTALL_LIBDIR}/pkgconfig /root)
configure_file(${PROJECT_SOURCE_DIR}/cmake/vecat.pc.in ${PROJECT_BINARY_DIR}/vecat.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/vecat.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# Debian package: cpack -G DEB (dependencies: the Debian packages of the libraries above).
set(CPACK_PACKAGE_NAME vecat)
set(CPACK_PACKAGE_VENDOR "vecat")
set(CPACK_PACKAGE_CONTACT "vecat maintainers <vecat@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION devel)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libfmt-dev, libyaml-cpp-dev, libpugixml-dev, libcap-dev")
if(VECAT_TELEMETRY)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", cyclonedds-dev")
endif()
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS OFF)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
include(CPack)
