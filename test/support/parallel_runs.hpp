#pragma once
// The benches' Monte Carlo runs on worker threads. A bad vehicle or scenario file throws
// ParamError in whichever run reads it first (every run would): the other workers then start no
// new run, and the error is rethrown on the calling thread once all have joined, so that main
// reports it and exits 2 instead of std::terminate.

#include <atomic>
#include <cstddef>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "common/params.hpp"

namespace alight::test {

/// Calls run_one(i) once for each i in [0, n) on `jobs` threads (at least one); rethrows the
/// first ParamError a run threw after every thread has joined.
template <class RunOne>
void run_parallel(size_t n, int jobs, RunOne run_one) {
  std::atomic<size_t> next{0};
  std::mutex error_mutex;
  std::optional<ParamError> config_error;
  const auto worker = [&] {
    try {
      for (size_t i = next++; i < n; i = next++) run_one(i);
    } catch (const ParamError& e) {
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!config_error) config_error = e;
      next = n;
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < (jobs > 0 ? jobs : 1); ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (config_error) throw *config_error;
}

}  // namespace alight::test
