# Included right after xsimd is found, by krs's own CMakeLists.txt and by the installed
# krsConfig.cmake.
#
# Debian's xsimd 8.1 package lists "xtl" in the xsimd target's INTERFACE_LINK_LIBRARIES without
# providing (or finding) an xtl target, so every consumer would link with -lxtl and fail. xtl is
# header-only and xsimd uses it only under XSIMD_ENABLE_XTL_COMPLEX, which krs never sets: use xtl's
# own target when it is installed, otherwise drop the dangling name.
if(TARGET xsimd AND NOT TARGET xtl)
    get_target_property(_krs_xsimd_links xsimd INTERFACE_LINK_LIBRARIES)
    if(_krs_xsimd_links AND "xtl" IN_LIST _krs_xsimd_links)
        find_package(xtl CONFIG QUIET)
        if(NOT TARGET xtl)
            list(REMOVE_ITEM _krs_xsimd_links xtl)
            set_property(TARGET xsimd PROPERTY INTERFACE_LINK_LIBRARIES "${_krs_xsimd_links}")
        endif()
    endif()
    unset(_krs_xsimd_links)
endif()
