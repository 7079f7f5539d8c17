# Embeds a scene file into a target as `std::string_view seiche::default_scene_json()`.
#
#   include(${CMAKE_CURRENT_SOURCE_DIR}/cmake/embed_default_scene.cmake)
#   seiche_embed_default_scene(seiche_core ${CMAKE_CURRENT_SOURCE_DIR}/../scenes/dam_break.json)
#
# The JSON is read at configure time and pasted into a raw string literal (core/src/scene/
# default_scene.cpp.in). The file is a CMAKE_CONFIGURE_DEPENDS, so editing it makes the next build
# re-run CMake, which regenerates the source; configure_file leaves the output untouched (and the
# object file up to date) when the JSON did not change.
function(seiche_embed_default_scene target json_file)
  get_filename_component(json_file "${json_file}" ABSOLUTE)
  if(NOT EXISTS "${json_file}")
    message(FATAL_ERROR "seiche_embed_default_scene: ${json_file} does not exist")
  endif()
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${json_file}")

  file(READ "${json_file}" SEICHE_SCENE_JSON)
  # The template closes the literal with )seiche_json" ; the text must not contain it.
  string(FIND "${SEICHE_SCENE_JSON}" ")seiche_json\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "seiche_embed_default_scene: ${json_file} contains the raw string delimiter )seiche_json\"")
  endif()
  set(SEICHE_SCENE_SOURCE "${json_file}")

  set(generated "${CMAKE_CURRENT_BINARY_DIR}/generated/default_scene.cpp")
  configure_file("${CMAKE_CURRENT_FUNCTION_LIST_DIR}/../src/scene/default_scene.cpp.in" "${generated}" @ONLY)
  target_sources(${target} PRIVATE "${generated}")
endfunction()
