#include "LaneWorkers.hpp"

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
