// Min/max decimation shared by the run and table reports: at most 2·n buckets, each covering
// `samples_per_bucket` samples. When all 2·n are used, neighbours merge and the span doubles, so
// memory stays flat whatever the run's length and every extreme survives.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cncore::io {

// Adds the one-sample bucket `s`. Bucket has a `samples` count; merge(into, from) combines two.
template <class Bucket, class Merge>
void add_to_buckets(std::vector<Bucket>& buckets, std::uint64_t& samples_per_bucket, std::size_t n,
                    const Bucket& s, Merge merge) {
  if (!buckets.empty() && buckets.back().samples < samples_per_bucket) {
    merge(buckets.back(), s);
    return;
  }
  if (buckets.size() == 2 * n) {
    for (std::size_t i = 0; i < n; ++i) {
      Bucket a = buckets[2 * i];
      merge(a, buckets[2 * i + 1]);
      buckets[i] = a;
    }
    buckets.resize(n);
    samples_per_bucket *= 2;
    if (buckets.back().samples < samples_per_bucket) {
      merge(buckets.back(), s);
      return;
    }
  }
  buckets.push_back(s);
}

}  // namespace cncore::io
