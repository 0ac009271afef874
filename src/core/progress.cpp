// SPDX-License-Identifier: Apache-2.0
#include "ido/core/progress.h"

#include "ido/core/error.h"

namespace ido {

void Progress::update(double fraction, std::string_view stage) {
  check();
  if (m_callback) m_callback(fraction, stage);
}

void Progress::check() const {
  if (cancelled()) throw Cancelled();
}

}  // namespace ido
