// SPDX-License-Identifier: Apache-2.0
// The machine's floor for a 1 kHz thread: a loop that does nothing but sleep_until the next
// millisecond, with and without SCHED_FIFO, counting wake-ups later than one period. The
// drilling session's haptic thread (bench/drill BM_HapticLoop, `ido drill`) cannot miss fewer
// deadlines than this loop does on the same machine under the same load.
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <thread>
#include <vector>

#include <benchmark/benchmark.h>

namespace {

// Args: SCHED_FIFO priority (0 = ordinary scheduling), seconds.
void BM_WakeLatency(benchmark::State& state) {
  const int priority = static_cast<int>(state.range(0));
  const int ticks = static_cast<int>(state.range(1)) * 1000;
  std::vector<double> late_us;
  late_us.reserve(static_cast<std::size_t>(ticks));
  bool realtime = false;
  for (auto _ : state) {
    std::thread worker([&] {
      if (priority > 0) {
        sched_param p{};
        p.sched_priority = priority;
        realtime = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
      }
      using clock = std::chrono::steady_clock;
      auto next = clock::now();
      for (int i = 0; i < ticks; ++i) {
        next += std::chrono::microseconds(1000);
        std::this_thread::sleep_until(next);
        late_us.push_back(std::chrono::duration<double, std::micro>(clock::now() - next).count());
      }
    });
    worker.join();
  }
  std::sort(late_us.begin(), late_us.end());
  const auto at = [&](double q) { return late_us[std::min(late_us.size() - 1, static_cast<std::size_t>(q * static_cast<double>(late_us.size())))]; };
  state.counters["realtime"] = realtime ? 1.0 : 0.0;
  // A wake-up later than one period is a missed 1 ms deadline for a haptic loop.
  state.counters["missed_1ms"] = static_cast<double>(late_us.end() - std::upper_bound(late_us.begin(), late_us.end(), 1000.0));
  state.counters["late_p50_us"] = at(0.5);
  state.counters["late_p99_us"] = at(0.99);
  state.counters["late_p99_9_us"] = at(0.999);
  state.counters["late_max_us"] = late_us.back();
}
BENCHMARK(BM_WakeLatency)->ArgsProduct({{0, 80}, {60}})->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
