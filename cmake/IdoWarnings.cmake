# SPDX-License-Identifier: Apache-2.0
# ido_set_warnings(target): the project's warning set; errors when IDO_WERROR is on.
function(ido_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
                         -Wno-maybe-uninitialized)
  if(IDO_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()
