# SPDX-License-Identifier: Apache-2.0
# Applies IDO_SANITIZE ("address,undefined" or "thread") to everything built below.
if(IDO_SANITIZE)
  add_compile_options(-fsanitize=${IDO_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=${IDO_SANITIZE})
endif()
