# cmake -DREADME=... -DSNIPPET=... -P check_readme_snippet.cmake
# Fails unless README contains the snippet file verbatim (so the documented usage compiles: the
# snippet is built as an example).
file(READ "${README}" readme)
file(READ "${SNIPPET}" snippet)
string(FIND "${readme}" "${snippet}" position)
if(position EQUAL -1)
    message(FATAL_ERROR "${README} does not contain ${SNIPPET} verbatim: update the README's usage block")
endif()
