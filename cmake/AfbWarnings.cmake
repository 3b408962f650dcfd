# afb_warnings(target): the project's warning set, applied to every target we build.
function(afb_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion)
  if(AFB_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
