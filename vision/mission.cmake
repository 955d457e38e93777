# Issue 6: the landing / ingress targets, the per-frame pipeline and the alight-vision node.
# Included (OPTIONAL) from vision/CMakeLists.txt.
add_library(alight_vision_mission STATIC
  ${CMAKE_CURRENT_LIST_DIR}/mission_params.cpp ${CMAKE_CURRENT_LIST_DIR}/landing_target.cpp
  ${CMAKE_CURRENT_LIST_DIR}/ingress_target.cpp ${CMAKE_CURRENT_LIST_DIR}/pipeline.cpp
  ${CMAKE_CURRENT_LIST_DIR}/diag_image.cpp)
target_include_directories(alight_vision_mission PUBLIC ${PROJECT_SOURCE_DIR})
target_link_libraries(alight_vision_mission PUBLIC alight_vision alight_common opencv_core
                                                   opencv_imgproc)
target_compile_options(alight_vision_mission PRIVATE -O2)

# The FrameResult -> target_t conversion (the node's, shared with tests and the closed loop).
add_library(alight_vision_msgs STATIC ${CMAKE_CURRENT_LIST_DIR}/convert.cpp
                                      ${CMAKE_CURRENT_LIST_DIR}/inputs.cpp)
target_link_libraries(alight_vision_msgs PUBLIC alight_vision_mission alight_msgs alight_lcmtypes)

alight_add_node(alight-vision SOURCES ${CMAKE_CURRENT_LIST_DIR}/vision_node.cpp
                LIBS alight_vision_msgs alight_msgs alight_node alight_lcmtypes)
