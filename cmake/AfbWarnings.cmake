# afb_warnings(target): the project's warning set, applied to every target we build.
function(afb_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion)
  # GCC 12 reports a false -Wrestrict inside libstdc++'s `"literal" + std::string` at -O2 (GCC bug 105651).
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_GREATER_EQUAL 12
     AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
  if(AFB_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
