# cmake -DROOT=<source dir> -P check_doc_citations.cmake
#
# Fails unless every document the repository's text files cite is in the repository: a reader who
# follows a citation must find the page. It reads the sources, build files, scripts and documents
# (include/ tests/ bench/ examples/ scripts/ cmake/ docs/ glsl/ fuzz/ except its corpus, and the
# top-level README.md and CMakeLists.txt) and checks four kinds of citation:
#   - a name ending in .md (`docs/hypertree_format.md`, a bare `README.md`), with an optional
#     `#section`: found relative to the citing file or to the root; a bare name may also be any
#     document of that name in the tree (scripts name `benchmarks.md` beside a docs/ variable);
#   - a relative link in markdown, `[text](path)` or `![alt](path)`, to any file;
#   - a rule cited by a document's upper-case name, `<NAME> rule <n>`, which needs <NAME>.md;
#   - in markdown, a source file named in code by a path with a folder (`include/krs/field.hpp`,
#     or one under include/, include/krs/ or include/hypertree/, as prose about a library says
#     `render/glsl.hpp`).
# Code in markdown (fenced blocks and inline spans) is not read for links.
# A `#section` must be a heading of the cited document (GitHub's anchor: lower case, punctuation
# dropped, spaces as hyphens) or an `<a id="...">` in it. Names are compared case-sensitively, as
# the file system and GitHub do.

cmake_minimum_required(VERSION 3.20) # IN_LIST, list(JOIN), policies of script mode

if(NOT ROOT)
    get_filename_component(ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
endif()

set(text_extensions hpp cpp h c txt cmake in md glsl py sh tree forest dict frag comp vert)
set(scanned_dirs include tests bench examples scripts cmake docs glsl fuzz .ci)
set(files "${ROOT}/README.md" "${ROOT}/CMakeLists.txt")
set(all_files ${files})
foreach(dir IN LISTS scanned_dirs)
    if(NOT IS_DIRECTORY "${ROOT}/${dir}")
        continue()
    endif()
    file(GLOB_RECURSE found LIST_DIRECTORIES false "${ROOT}/${dir}/*")
    foreach(f IN LISTS found)
        file(RELATIVE_PATH relative "${ROOT}" "${f}")
        if(relative MATCHES "^fuzz/(corpus|crashers)/[^/]+/") # fuzz inputs are data, not text
            continue()
        endif()
        list(APPEND all_files "${f}")
        get_filename_component(name "${f}" NAME)
        string(REGEX MATCH "[^.]+$" extension "${name}")
        if(name STREQUAL "run" OR extension IN_LIST text_extensions)
            list(APPEND files "${f}")
        endif()
    endforeach()
endforeach()

# Every file name of the tree, for a bare document name.
set(all_names "")
foreach(f IN LISTS all_files)
    get_filename_component(name "${f}" NAME)
    list(APPEND all_names "${name}")
endforeach()

# The anchors of a markdown file: GitHub's heading slugs and explicit <a id=...> / <a name=...>.
function(anchors_of path out)
    file(STRINGS "${path}" lines)
    set(result "")
    foreach(line IN LISTS lines)
        if(line MATCHES "^#+[ \t]+(.*)$")
            string(TOLOWER "${CMAKE_MATCH_1}" slug)
            string(REGEX REPLACE "[^a-z0-9 _-]" "" slug "${slug}")
            string(REPLACE " " "-" slug "${slug}")
            list(APPEND result "${slug}")
        endif()
        string(REGEX MATCHALL "<a (id|name)=\"[^\"]+\"" explicit "${line}")
        foreach(a IN LISTS explicit)
            string(REGEX REPLACE "^<a (id|name)=\"([^\"]+)\"$" "\\2" a "${a}")
            list(APPEND result "${a}")
        endforeach()
    endforeach()
    set(${out} "${result}" PARENT_SCOPE)
endfunction()

set(problems "")
# Resolves `target` (a path with an optional #section) cited in `file`; appends to problems.
macro(check_citation file target bare_name_anywhere)
    set(path "${target}")
    set(section "")
    if(path MATCHES "^([^#]*)#(.*)$")
        set(path "${CMAKE_MATCH_1}")
        set(section "${CMAKE_MATCH_2}")
    endif()
    get_filename_component(dir "${file}" DIRECTORY)
    set(resolved "")
    if(path STREQUAL "")
        set(resolved "${file}") # a link to a section of the same document
    elseif(NOT IS_ABSOLUTE "${path}")
        foreach(base IN ITEMS "${dir}" "${ROOT}")
            get_filename_component(candidate "${base}/${path}" ABSOLUTE)
            # EXISTS ignores case on some file systems: compare the name as listed.
            get_filename_component(parent "${candidate}" DIRECTORY)
            get_filename_component(name "${candidate}" NAME)
            file(GLOB listed RELATIVE "${parent}" "${parent}/*")
            string(FIND "${candidate}/" "${ROOT}/" inside)
            if(name IN_LIST listed AND inside EQUAL 0)
                set(resolved "${candidate}")
                break()
            endif()
        endforeach()
        if(NOT resolved AND ${bare_name_anywhere} AND NOT path MATCHES "/" AND path IN_LIST all_names)
            set(resolved "${path}") # named, not located: its sections are not checked
        endif()
    endif()
    file(RELATIVE_PATH shown "${ROOT}" "${file}")
    if(NOT resolved)
        list(APPEND problems "${shown}: cites ${target}, which is not in the repository")
    elseif(section AND IS_ABSOLUTE "${resolved}" AND resolved MATCHES "\\.md$")
        anchors_of("${resolved}" anchors)
        if(NOT section IN_LIST anchors)
            file(RELATIVE_PATH cited_file "${ROOT}" "${resolved}")
            list(APPEND problems "${shown}: cites ${target}, but ${cited_file} has no section #${section}")
        endif()
    endif()
endmacro()

set(checked 0)
foreach(file IN LISTS files)
    file(READ "${file}" text)
    # Semicolons and square brackets would split or join CMake list items: none is part of a
    # citation, so they become a space and angle brackets (a markdown link reads `>(path)`).
    string(REPLACE ";" " " text "${text}")
    string(REPLACE "[" "<" text "${text}")
    string(REPLACE "]" ">" text "${text}")
    # A path may start with a variable (`${PROJECT_SOURCE_DIR}/README.md`): one of the tree's roots.
    string(REGEX MATCHALL "(\\$\\{?[A-Za-z_]+\\}?)?[A-Za-z0-9_./-]*[A-Za-z0-9_-]\\.md(#[A-Za-z0-9_-]+)?" cited
           "${text}")
    foreach(c IN LISTS cited)
        if(c MATCHES "^//") # the path part of a URL
            continue()
        endif()
        string(REGEX REPLACE "^\\$\\{?[A-Za-z_]+\\}?/?" "" c "${c}")
        check_citation("${file}" "${c}" TRUE)
        math(EXPR checked "${checked} + 1")
    endforeach()
    if(file MATCHES "\\.md$")
        # Code is not a link: `convert_float<float>(x)` reads `>(x)` once brackets are angles.
        # Fenced blocks and inline code spans go first.
        string(REGEX REPLACE "```[^`]*```" "" prose "${text}")
        string(REGEX REPLACE "`[^`\n]*`" "" prose "${prose}")
        string(REGEX MATCHALL ">\\([^) \t\n]+\\)" links "${prose}")
        foreach(link IN LISTS links)
            string(REGEX REPLACE "^>\\((.*)\\)$" "\\1" target "${link}")
            if(target MATCHES "^[a-z]+:" OR target MATCHES "\\.md(#|$)") # URLs; .md handled above
                continue()
            endif()
            check_citation("${file}" "${target}" FALSE)
            math(EXPR checked "${checked} + 1")
        endforeach()
    endif()
    if(file MATCHES "\\.md$")
        # A source file named by its path in code (`include/krs/core/lanes.hpp`, `krs/trace/ray.hpp`,
        # `tests/CMakeLists.txt`): a path with a folder, relative to the document, the root, or
        # include/, include/krs/ or include/hypertree/. Templates (`store/<name>_store.hpp`) are not
        # paths.
        string(REGEX MATCHALL "`[A-Za-z0-9_.-]+(/[A-Za-z0-9_.-]+)+\\.(hpp|cpp|cmake|sh|py|txt|glsl)`" code_paths
               "${text}")
        foreach(code_path IN LISTS code_paths)
            string(REPLACE "`" "" code_path "${code_path}")
            foreach(prefix IN ITEMS include include/krs include/hypertree)
                if(NOT EXISTS "${ROOT}/${code_path}" AND EXISTS "${ROOT}/${prefix}/${code_path}")
                    set(code_path "${prefix}/${code_path}")
                endif()
            endforeach()
            check_citation("${file}" "${code_path}" FALSE)
            math(EXPR checked "${checked} + 1")
        endforeach()
    endif()
    string(REGEX MATCHALL "[A-Z][A-Z_]+[ \t\n/#*]+rule [0-9]" rules "${text}")
    foreach(r IN LISTS rules)
        string(REGEX REPLACE "^([A-Z][A-Z_]+).*$" "\\1" named "${r}")
        set(named "${named}.md")
        string(REGEX REPLACE "[ \t\n/#*]+" " " r "${r}")
        if(NOT named IN_LIST all_names)
            file(RELATIVE_PATH shown "${ROOT}" "${file}")
            list(APPEND problems "${shown}: cites '${r}' of ${named}, which is not in the repository")
        endif()
        math(EXPR checked "${checked} + 1")
    endforeach()
endforeach()

if(problems)
    list(REMOVE_DUPLICATES problems)
    list(JOIN problems "\n  " listed)
    message(FATAL_ERROR "documents cited but missing (cite a file of this repository, e.g. a section of "
                        "docs/design.md):\n  ${listed}")
endif()
list(LENGTH files scanned)
message(STATUS "${checked} citations in ${scanned} files resolve")
