# Writes OUT, a header defining DSB_GIT_SHA: the 12-digit commit of SOURCE_DIR's checkout, with
# "-dirty" when tracked files differ from it, or "unknown" outside a git checkout. Run by the
# dsb_git_sha target at every build, so that runs and `--version` name the commit the binary was
# built from, not the one CMake was configured at; the file is rewritten only when its text
# changes, so an unchanged commit recompiles nothing.
execute_process(COMMAND git rev-parse --short=12 HEAD
                WORKING_DIRECTORY ${SOURCE_DIR}
                OUTPUT_VARIABLE sha OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(sha)
  execute_process(COMMAND git status --porcelain --untracked-files=no
                  WORKING_DIRECTORY ${SOURCE_DIR}
                  OUTPUT_VARIABLE changes OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(changes)
    string(APPEND sha "-dirty")
  endif()
else()
  set(sha "unknown")
endif()
set(text "#pragma once\n// generated at build time by cmake/git_sha.cmake: the commit this binary was built from\n#define DSB_GIT_SHA \"${sha}\"\n")
set(old "")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT old STREQUAL text)
  file(WRITE ${OUT} "${text}")
endif()
