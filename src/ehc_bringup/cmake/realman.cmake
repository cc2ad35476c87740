# RealMan deployment: rm_driver arm adapter and Water2 base bridge (issue 7).
# Included by ../CMakeLists.txt after the package's own core library.

# ---------------------------------------------------------------- ROS-free core library
add_library(ehc_realman_core
  src/core/realman_joint_streamer.cpp
  src/core/realman_adapter_config.cpp
  src/core/water2_protocol.cpp
  src/core/water2_client.cpp
  src/core/water2_base_bridge.cpp
)
target_include_directories(ehc_realman_core PUBLIC include ${EIGEN3_INCLUDE_DIR})
target_link_libraries(ehc_realman_core PUBLIC ehc_control_core)

# ---------------------------------------------------------------- nodes (thin ROS wrappers)
function(ehc_realman_node name)
  add_executable(${name} src/nodes/${name}.cpp)
  target_include_directories(${name} PRIVATE ${catkin_INCLUDE_DIRS})
  target_link_libraries(${name} ehc_realman_core ${catkin_LIBRARIES})
  add_dependencies(${name} ${catkin_EXPORTED_TARGETS})
endfunction()
ehc_realman_node(rm_arm_adapter)
ehc_realman_node(water2_base_bridge)

# ---------------------------------------------------------------- tests (loopback only)
if(CATKIN_ENABLE_TESTING)
  find_package(rostest REQUIRED)

  function(ehc_realman_gtest name)
    catkin_add_gtest(${name} test/${name}.cpp)
    target_include_directories(${name} PRIVATE ${catkin_INCLUDE_DIRS} test)
    target_link_libraries(${name} ehc_realman_core ${catkin_LIBRARIES} gtest_main)
    add_dependencies(${name} ${catkin_EXPORTED_TARGETS})
    target_compile_definitions(${name} PRIVATE EHC_CONFIG_DIR="${EHC_CONFIG_DIR}")
  endfunction()
  ehc_realman_gtest(test_rm_msgs_md5)
  ehc_realman_gtest(test_realman_joint_streamer)
  ehc_realman_gtest(test_water2_protocol)
  ehc_realman_gtest(test_water2_bridge_core)

  # rostest: node under test + a test node with a fake rm_driver / fake Water2 server.
  function(ehc_realman_rostest name)
    add_rostest_gtest(${name} test/${name}.test test/${name}.cpp)
    target_include_directories(${name} PRIVATE ${catkin_INCLUDE_DIRS} test)
    target_link_libraries(${name} ehc_realman_core ${catkin_LIBRARIES})
    add_dependencies(${name} ${catkin_EXPORTED_TARGETS} rm_arm_adapter water2_base_bridge)
    target_compile_definitions(${name} PRIVATE EHC_CONFIG_DIR="${EHC_CONFIG_DIR}"
      WATER2_BRIDGE_BIN="$<TARGET_FILE:water2_base_bridge>")
  endfunction()
  ehc_realman_rostest(test_rm_arm_adapter_node)
  ehc_realman_rostest(test_water2_base_bridge_node)
  ehc_realman_rostest(test_run_realman_script)
  # Closed loop on wall time: ehc_controller_node (timer trigger) -> adapter / bridge -> fake
  # rm_driver + fake Water2 server -> /joint_states + /odom -> controller.
  ehc_realman_rostest(test_realman_closed_loop)
  add_dependencies(test_realman_closed_loop ehc_controller_node)
endif()
