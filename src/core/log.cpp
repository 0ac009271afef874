// SPDX-License-Identifier: Apache-2.0
#include "ido/core/log.h"

#include <atomic>

#include <spdlog/sinks/null_sink.h>

namespace ido {
namespace {
std::shared_ptr<spdlog::logger> make_silent() {
  return std::make_shared<spdlog::logger>("ido", std::make_shared<spdlog::sinks::null_sink_mt>());
}
// The active logger; replaced atomically so worker threads never see a torn pointer.
std::shared_ptr<spdlog::logger>& slot() {
  static std::shared_ptr<spdlog::logger> current = make_silent();
  return current;
}
}  // namespace

spdlog::logger& logger() { return *std::atomic_load(&slot()); }

void set_logger(std::shared_ptr<spdlog::logger> l) {
  std::atomic_store(&slot(), l ? std::move(l) : make_silent());
}

}  // namespace ido
