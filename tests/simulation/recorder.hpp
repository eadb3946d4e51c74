// An observer that keeps every sample and block of a run, and where each block was announced
// (run_program tests, single-thread and threaded).
#pragma once

#include <cstddef>
#include <vector>

#include "simulation/run.hpp"

namespace cncore::sim::test {

struct Recorder : SampleObserver {
  std::vector<motion::Sample> samples;
  std::vector<Block> blocks;
  std::vector<std::size_t> samples_at_block;  // samples seen when each block was announced
  bool finished = false;
  void on_block(const Block& b) override {
    blocks.push_back(b);
    samples_at_block.push_back(samples.size());
  }
  void on_sample(const motion::Sample& s) override { samples.push_back(s); }
  void on_finish() override { finished = true; }
};

}  // namespace cncore::sim::test
