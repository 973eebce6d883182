# Writes OUT with the source tree's `git describe --always --dirty` (run at every build, so
# that results name the commit they were built from; the file changes only when it does).
find_package(Git QUIET)
set(git "unknown")
if(GIT_FOUND)
  execute_process(COMMAND ${GIT_EXECUTABLE} describe --always --dirty WORKING_DIRECTORY ${SRC}
                  OUTPUT_VARIABLE described OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc)
  if(rc EQUAL 0 AND described)
    set(git "${described}")
  endif()
endif()
set(text "// Generated at build time by experiments/build_git.cmake.\n#pragma once\n#define DEFORMLAB_GIT \"${git}\"\n")
set(old "")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT old STREQUAL text)
  file(WRITE ${OUT} "${text}")
endif()
