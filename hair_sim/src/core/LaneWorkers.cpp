#include "LaneWorkers.hpp"

#include <algorithm>
#include <cmath>

namespace hair_sim {

LaneWorkers::LaneWorkers(int helpers) {
  for (int t = 0; t < helpers; ++t) threads_.emplace_back(&LaneWorkers::loop, this);
}

LaneWorkers::~LaneWorkers() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    quit_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : threads_) t.join();
}

void LaneWorkers::start(std::size_t blocks, void (*run)(void*, std::size_t), void* context) {
  if (blocks > done_size_) {
    done_.reset(new std::atomic<long>[blocks]);
    for (std::size_t b = 0; b < blocks; ++b) done_[b].store(0, std::memory_order_relaxed);
    done_size_ = blocks;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    run_ = run;
    context_ = context;
    blocks_ = blocks;
    next_.store(0, std::memory_order_relaxed);
    ++generation_;
    busy_.store(helpers(), std::memory_order_relaxed);
    active_generation_.store(generation_, std::memory_order_release);
  }
  wake_.notify_all();
}

bool LaneWorkers::runOne() {
  const std::size_t b = next_.fetch_add(1, std::memory_order_relaxed);
  if (b >= blocks_) return false;
  run_(context_, b);
  done_[b].store(active_generation_.load(std::memory_order_relaxed), std::memory_order_release);
  return true;
}

void LaneWorkers::waitFor(std::size_t b) {
  const long generation = active_generation_.load(std::memory_order_relaxed);
  while (done_[b].load(std::memory_order_acquire) != generation)
    if (!runOne()) std::this_thread::yield();  // a helper is on it
}

void LaneWorkers::finish() {
  while (runOne()) {
  }
  const long generation = active_generation_.load(std::memory_order_relaxed);
  for (std::size_t b = 0; b < blocks_; ++b)
    while (done_[b].load(std::memory_order_acquire) != generation) std::this_thread::yield();
  while (busy_.load(std::memory_order_acquire) != 0) std::this_thread::yield();
}

void LaneWorkers::startRuns(std::size_t runs0, std::size_t runs1) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++run_generation_;
  const std::size_t runs[2] = {runs0, runs1};
  for (int g = 0; g < 2; ++g) {
    RunGroup& group = run_groups_[g];
    if (runs[g] > group.done_size) {
      group.done.reset(new std::atomic<long>[runs[g]]);
      for (std::size_t r = 0; r < runs[g]; ++r) group.done[r].store(0, std::memory_order_relaxed);
      group.done_size = runs[g];
    }
    group.front = 0;
    group.back = runs[g];
  }
}

bool LaneWorkers::claimRun(int g, bool from_back, std::size_t& run) {
  std::lock_guard<std::mutex> lock(mutex_);
  RunGroup& group = run_groups_[g];
  if (group.front >= group.back) return false;
  run = from_back ? --group.back : group.front++;
  return true;
}

void LaneWorkers::markRunDone(int g, std::size_t run) {
  run_groups_[g].done[run].store(run_generation_, std::memory_order_release);
}

void LaneWorkers::waitRunDone(int g, std::size_t run) {
  while (run_groups_[g].done[run].load(std::memory_order_acquire) != run_generation_)
    std::this_thread::yield();
}

void LaneWorkers::settle(double end0, double end1, double lent_seconds, int lent, int runs0, int runs1) {
  if (lent > 0) balance.run_seconds = lent_seconds / lent;
  if (balance.run_seconds <= 0.0) balance.run_seconds = 1e-5;  // (a first guess: 10 us)
  // end1 > end0: group 1's sweep ended later; moving k runs to group 0's sweep evens them for
  // k = (end1 - end0) / (2 run_seconds). Half of that, for a steady balance (within the runs there are).
  const double runs = static_cast<double>(runs0 + runs1);
  const double k = std::max(-runs, std::min(runs, 0.25 * (end1 - end0) / balance.run_seconds));
  balance.lend = std::max(-runs0, std::min(runs1, balance.lend + static_cast<int>(std::lround(k))));
}

void LaneWorkers::loop() {
  long seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return quit_ || generation_ != seen; });
      if (quit_) return;
      seen = generation_;
    }
    while (runOne()) {
    }
    busy_.fetch_sub(1, std::memory_order_acq_rel);
  }
}

}  // namespace hair_sim
