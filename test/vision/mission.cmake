# Tests of the landing / ingress targets and the pipeline (issue 6); included (OPTIONAL) from
# test/vision/CMakeLists.txt. They render views with the simulator's library.
if(TARGET alight_vision_mission AND TARGET alight_sim AND TARGET alight_sim_params)
  alight_add_gtest(vision_landing_mission_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/landing_mission_test.cpp
    LIBS alight_vision_mission alight_sim alight_sim_params
    LABELS vision TIMEOUT 120)
endif()
if(TARGET alight_vision_mission AND TARGET alight_sim AND TARGET alight_sim_params)
  alight_add_gtest(vision_ingress_mission_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/ingress_mission_test.cpp
    LIBS alight_vision_mission alight_sim alight_sim_params opencv_imgcodecs
    LABELS vision TIMEOUT 120)
endif()
if(TARGET alight_vision_mission)
  alight_add_gtest(vision_ingress_target_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/ingress_target_test.cpp
    LIBS alight_vision_mission opencv_imgproc
    LABELS vision)
endif()
if(TARGET alight_vision_msgs)
  alight_add_gtest(vision_convert_test
    SOURCES ${CMAKE_CURRENT_LIST_DIR}/convert_test.cpp ${CMAKE_CURRENT_LIST_DIR}/inputs_test.cpp
    LIBS alight_vision_msgs
    LABELS vision)
endif()
