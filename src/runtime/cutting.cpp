#include "runtime/cutting.hpp"

#include <algorithm>
#include <limits>

namespace cncore::runtime {

CuttingThread::CuttingThread(const MachineConfig& machine, std::size_t ring_cycles, bool start)
    : machine_(machine), ring_(ring_cycles) {
  sim_.emplace(machine_, "serve");
  publish();
  if (start) this->start();
}

CuttingThread::~CuttingThread() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

void CuttingThread::start() {
  if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
}

void CuttingThread::on_cycle(std::uint64_t n, motion::Sample& s, Status& status) noexcept {
  CutSample c;
  c.cycle = n;
  c.position = Vec3{s.position[kX], s.position[kY], s.position[kZ]};
  if (s.aux_letter == 'T') c.tool_selected = s.aux_value;
  c.tool_change = s.aux_letter == 'M' && s.aux_value == 6;
  if (status.job != last_job_) {
    last_job_ = status.job;
    c.fresh_stock = !status.job_mdi;
  }
  if (has_pending_) {
    // Merged: the newest position, every tool event, the cycles it stands for.
    pending_.cycle = n;
    ++pending_.cycles;
    pending_.position = c.position;
    if (c.tool_selected >= 0) pending_.tool_selected = c.tool_selected;
    pending_.tool_change = pending_.tool_change || c.tool_change;
    pending_.fresh_stock = pending_.fresh_stock || c.fresh_stock;
  } else {
    pending_ = c;
  }
  has_pending_ = !ring_.try_push(pending_);
  if (has_pending_) ++coalesced_;
  const double load = load_pct_.load(std::memory_order_relaxed);
  status.load_pct = load;
  status.cutting_coalesced = coalesced_;
  status.cutting_lag_cycles = n - std::min(n, taken_cycle_.load(std::memory_order_relaxed));
  s.load_pct = load;
}

std::shared_ptr<const HeightMapGrid> CuttingThread::heightmap() const {
  const std::lock_guard lock(map_mutex_);
  return map_;
}

void CuttingThread::run() {
  CutSample c;
  while (!stop_.load(std::memory_order_acquire)) {
    bool took = false;
    // A bounded batch, so that a backlog does not hold back the map's publication.
    for (int k = 0; k < 4096 && ring_.try_pop(c); ++k) {
      take(c);
      took = true;
    }
    if (fresh_requested_.exchange(false, std::memory_order_acq_rel)) make_fresh();
    if (changed_ && std::chrono::steady_clock::now() - published_at_ >= kPublishEvery) publish();
    if (!took) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// One sample: c.cycles cycles of the simulator (its load meter averages over cycles). Tool
// events first, where the tool stood; then the sweep to the new position; then the merged
// cycles' standstill, which lets the meter's window see their time.
void CuttingThread::take(const CutSample& c) {
  if (c.fresh_stock) make_fresh();
  if (!have_last_) {  // the simulator starts where the tool is (it may be inside the stock)
    last_ = c.position;
    have_last_ = true;
  }
  std::uint32_t used = 0;
  if (c.tool_selected >= 0 && c.tool_change && c.cycles > 1) {
    step(last_, c.tool_selected, false);
    step(last_, -1, true);
    used = 2;
  } else if (c.tool_selected >= 0 || c.tool_change) {
    step(last_, c.tool_selected, c.tool_change);
    used = 1;
  }
  if (used == 0 || !(c.position == last_)) {
    step(c.position, -1, false);
    ++used;
  }
  for (; used < c.cycles; ++used) step(last_, -1, false);
  load_pct_.store(sim_->last_load_pct(), std::memory_order_relaxed);
  taken_cycle_.store(c.cycle, std::memory_order_relaxed);
  cycles_done_.fetch_add(c.cycles, std::memory_order_release);
}

void CuttingThread::step(const Vec3& p, double tool_selected, bool tool_change) {
  motion::Sample s;
  s.position[kX] = p.x;
  s.position[kY] = p.y;
  s.position[kZ] = p.z;
  if (tool_selected >= 0) {
    s.aux_letter = 'T';
    s.aux_value = tool_selected;
  } else if (tool_change) {
    s.aux_letter = 'M';
    s.aux_value = 6;
  }
  sim_->process(s);
  last_ = p;
  if (sim_->last_cycle_removed_mm3() > 0) changed_ = true;
}

void CuttingThread::make_fresh() {
  sim_->map() = cut::HeightMap::from_stock(machine_.cutting.stock);
  changed_ = true;
  published_at_ = {};  // the fresh stock is shown at once
}

// The map for the page: the lowest cell of each k×k block when it is larger than kMaxSide a side,
// so that every cut stays visible.
void CuttingThread::publish() {
  const cut::HeightMap& m = sim_->map();
  auto g = std::make_shared<HeightMapGrid>();
  const std::size_t side = HeightMapGrid::kMaxSide;
  const std::size_t k = std::max<std::size_t>(1, (std::max(m.nx(), m.ny()) + side - 1) / side);
  g->nx = (m.nx() + k - 1) / k;
  g->ny = (m.ny() + k - 1) / k;
  g->cell_mm = m.cell_mm() * static_cast<double>(k);
  g->x0_mm = m.x0_mm();
  g->y0_mm = m.y0_mm();
  g->bottom_z_mm = m.bottom_z_mm();
  g->top_z_mm = m.top_z_mm();
  g->heights_mm.assign(g->nx * g->ny, std::numeric_limits<float>::infinity());
  for (std::size_t j = 0; j < m.ny(); ++j) {
    float* row = &g->heights_mm[(j / k) * g->nx];
    for (std::size_t i = 0; i < m.nx(); ++i) row[i / k] = std::min(row[i / k], m.at(i, j));
  }
  g->version = version_.load(std::memory_order_relaxed) + 1;
  {
    const std::lock_guard lock(map_mutex_);
    map_ = std::move(g);
  }
  version_.fetch_add(1, std::memory_order_release);
  changed_ = false;
  published_at_ = std::chrono::steady_clock::now();
}

}  // namespace cncore::runtime
