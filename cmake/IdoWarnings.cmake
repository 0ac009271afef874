# SPDX-License-Identifier: Apache-2.0
# ido_set_warnings(target): the project's warning set; errors when IDO_WERROR is on.
function(ido_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
                         -Wno-maybe-uninitialized)
  # GCC 12 reports -Wrestrict false positives inside std::string concatenation at -O3
  # (GCC bug 105329); the warning says nothing about our code there.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
  if(IDO_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
