# FindLCM.cmake -- LCM 1.3.1 ships no CMake config, and its lcm.pc pulls in glib.
# Defines LCM_FOUND, LCM_INCLUDE_DIRS, LCM_LIBRARIES, LCM_GEN_EXECUTABLE, LCM_JAR
# and the imported target LCM::lcm.
find_path(LCM_INCLUDE_DIR NAMES lcm/lcm-cpp.hpp)
find_library(LCM_LIBRARY NAMES lcm)
find_program(LCM_GEN_EXECUTABLE NAMES lcm-gen)
find_file(LCM_JAR NAMES lcm.jar PATHS /usr/share/java /usr/local/share/java NO_DEFAULT_PATH)

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(LCM REQUIRED_VARS LCM_INCLUDE_DIR LCM_LIBRARY LCM_GEN_EXECUTABLE)

if(LCM_FOUND)
  set(LCM_INCLUDE_DIRS ${LCM_INCLUDE_DIR})
  set(LCM_LIBRARIES ${LCM_LIBRARY})
  if(NOT TARGET LCM::lcm)
    add_library(LCM::lcm UNKNOWN IMPORTED)
    set_target_properties(LCM::lcm PROPERTIES
      IMPORTED_LOCATION "${LCM_LIBRARY}"
      INTERFACE_INCLUDE_DIRECTORIES "${LCM_INCLUDE_DIR}")
  endif()
endif()
mark_as_advanced(LCM_INCLUDE_DIR LCM_LIBRARY LCM_GEN_EXECUTABLE LCM_JAR)
