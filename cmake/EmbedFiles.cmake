# deformlab_embed(TARGET <lib> NAMESPACE <ns> FILES <f>...): builds a static library whose
# generated source holds each file's text as `std::string_view <ns>::<stem>`, with a lookup
# table `<ns>::find(name)`; the files are the sources of truth, the binary carries them.
function(deformlab_embed)
  cmake_parse_arguments(E "" "TARGET;NAMESPACE" "FILES" ${ARGN})
  set(out ${CMAKE_CURRENT_BINARY_DIR}/${E_TARGET}.cpp)
  set(hdr ${CMAKE_CURRENT_BINARY_DIR}/include/${E_TARGET}.hpp)
  # The list reaches the script joined by "|": a ";" would split the command.
  list(JOIN E_FILES "|" files)
  add_custom_command(
    OUTPUT ${out} ${hdr}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out} -DHDR=${hdr} -DNS=${E_NAMESPACE}
            "-DFILES=${files}" -P ${PROJECT_SOURCE_DIR}/cmake/EmbedScript.cmake
    DEPENDS ${E_FILES} ${PROJECT_SOURCE_DIR}/cmake/EmbedScript.cmake
    COMMENT "Embedding ${E_TARGET}" VERBATIM)
  add_library(${E_TARGET} STATIC ${out})
  target_include_directories(${E_TARGET} PUBLIC ${CMAKE_CURRENT_BINARY_DIR}/include)
endfunction()
