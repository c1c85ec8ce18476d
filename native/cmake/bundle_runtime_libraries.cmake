# cmake -DLIBRARY=<path> -DALLOWED=<soname;...> -P bundle_runtime_libraries.cmake
#
# Copies every shared library LIBRARY needs, directly or through another, except those named in
# ALLOWED (the C and C++ runtimes every Linux system has), into LIBRARY's folder under its SONAME,
# where LIBRARY's RUNPATH $ORIGIN finds it. Libraries of an earlier build that are no longer
# needed are removed first, so the folder holds exactly LIBRARY and what it needs. Resolved on this
# machine, as its dynamic loader would.
if(NOT LIBRARY OR NOT ALLOWED)
  message(FATAL_ERROR "usage: cmake -DLIBRARY=<path> -DALLOWED=<soname;...> -P ${CMAKE_CURRENT_LIST_FILE}")
endif()
get_filename_component(folder "${LIBRARY}" DIRECTORY)
get_filename_component(library_name "${LIBRARY}" NAME)

set(allowed_patterns)
foreach(name IN LISTS ALLOWED)
  string(REPLACE "." "\\." pattern "${name}")
  string(REPLACE "+" "\\+" pattern "${pattern}")
  list(APPEND allowed_patterns "^${pattern}$")
endforeach()

# Earlier copies go first: RUNPATH $ORIGIN would find them, and they must come from the system.
file(GLOB present RELATIVE "${folder}" "${folder}/*")
foreach(name IN LISTS present)
  if(NOT name STREQUAL library_name)
    file(REMOVE_RECURSE "${folder}/${name}")
  endif()
endforeach()

file(GET_RUNTIME_DEPENDENCIES
  LIBRARIES "${LIBRARY}"
  RESOLVED_DEPENDENCIES_VAR resolved
  UNRESOLVED_DEPENDENCIES_VAR unresolved
  PRE_EXCLUDE_REGEXES ${allowed_patterns})
if(unresolved)
  message(FATAL_ERROR "${library_name} needs libraries this system does not have: ${unresolved}")
endif()

set(bundled)
foreach(dependency IN LISTS resolved)
  # Found under the name a NEEDED entry gives (the SONAME); copied as the file it links to.
  get_filename_component(name "${dependency}" NAME)
  file(REAL_PATH "${dependency}" real)
  file(COPY_FILE "${real}" "${folder}/${name}")
  list(APPEND bundled "${name}")
endforeach()

list(SORT bundled)
message(STATUS "${library_name} bundles: ${bundled}")
