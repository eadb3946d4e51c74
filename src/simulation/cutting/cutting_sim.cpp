#include "simulation/cutting/cutting_sim.hpp"

#include <fmt/format.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/error.hpp"

namespace cncore::cut {

namespace {

const ToolSpec& initial_tool(const CuttingConfig& c) {
  if (c.tools.empty()) {
    throw std::invalid_argument("cutting simulation: the tool table ([[tools]]) is empty");
  }
  if (c.default_tool != 0) {
    if (const ToolSpec* t = c.find_tool(c.default_tool)) return *t;
  }
  return c.tools.front();
}

std::string tool_numbers(const CuttingConfig& c) {
  std::string s;
  for (const ToolSpec& t : c.tools) s += (s.empty() ? "" : ", ") + std::to_string(t.number);
  return s;
}

}  // namespace

CuttingSimulator::CuttingSimulator(const MachineConfig& machine, std::string program_path)
    : config_(&machine.cutting),
      program_(std::move(program_path)),
      map_(HeightMap::from_stock(machine.cutting.stock)),
      tool_(initial_tool(machine.cutting)),
      profile_(ToolProfile::of(tool_)),
      selected_(tool_.number),
      kc_n_mm2_(machine.cutting.effective_kc_n_mm2()),
      period_s_(machine.period_s) {
  if (!(kc_n_mm2_ > 0)) {
    throw std::invalid_argument("cutting simulation: unknown material " + machine.cutting.material);
  }
  const auto n = static_cast<std::size_t>(
      std::max(1.0, std::round(machine.cutting.load_window_s / machine.period_s)));
  window_.assign(n, 0.0);
}

void CuttingSimulator::on_block(const Block& b) {
  if (b.kind != BlockKind::kAux || b.aux_letter != 'T') return;
  const double v = b.aux_value;
  if (v < 0 || v > 4e9 || config_->find_tool(static_cast<std::uint32_t>(v)) == nullptr) {
    throw InputError(program_, b.line, b.col,
                     fmt::format("tool T{:g} is not in the tool table ([[tools]] of the machine "
                                 "configuration lists {})",
                                 v, tool_numbers(*config_)));
  }
}

void CuttingSimulator::select_tool(std::uint32_t number) noexcept {
  const ToolSpec* t = config_->find_tool(number);
  if (t == nullptr || *t == tool_) return;
  tool_ = *t;
  profile_ = ToolProfile::of(tool_);
  ++stats_.tool_changes;
}

void CuttingSimulator::on_sample(const motion::Sample& sample) {
  motion::Sample copy = sample;
  process(copy);
}

void CuttingSimulator::process(motion::Sample& s) noexcept {
  if (s.aux_letter == 'T' && s.aux_value >= 0) selected_ = static_cast<std::uint32_t>(s.aux_value);
  if (s.aux_letter == 'M' && s.aux_value == 6) select_tool(selected_);

  const Vec3 p{s.position[kX], s.position[kY], s.position[kZ]};
  double removed = 0;
  if (!have_position_) {
    removed = map_.sweep(profile_, p, p);  // the tool may start inside the stock
    have_position_ = true;
  } else if (!(p == last_)) {
    removed = map_.sweep(profile_, last_, p);
  }
  last_ = p;
  last_removed_mm3_ = removed;

  // Moving window: MRR = Σ removed over the last n cycles / (n·τ).
  window_sum_ += removed - window_[window_next_];
  window_[window_next_] = removed;
  window_next_ = (window_next_ + 1) % window_.size();
  if (window_sum_ < 1e-12) window_sum_ = 0;  // no drift below zero after a cut ends
  mrr_mm3_s_ = window_sum_ / (static_cast<double>(window_.size()) * period_s_);
  load_pct_ = load_from_mrr(mrr_mm3_s_, kc_n_mm2_, config_->spindle_power_kw);

  stats_.removed_mm3 += removed;
  stats_.peak_mrr_mm3_s = std::max(stats_.peak_mrr_mm3_s, mrr_mm3_s_);
  stats_.peak_load_pct = std::max(stats_.peak_load_pct, load_pct_);
  if (load_pct_ > 0) {
    stats_.load_sum_pct += load_pct_;
    ++stats_.cutting_cycles;
  }
  ++stats_.cycles;
  s.load_pct = load_pct_;
}

double CuttingSimulator::load_pct(double /*t_s*/, double /*path_s_mm*/,
                                  double /*feed_mm_min*/) noexcept {
  return load_pct_;
}

void CuttingStage::on_block(const Block& block) {
  sim_->on_block(block);
  for (sim::SampleObserver* o : downstream_) o->on_block(block);
}

void CuttingStage::on_sample(const motion::Sample& sample) {
  motion::Sample s = sample;
  sim_->process(s);
  for (sim::SampleObserver* o : downstream_) o->on_sample(s);
}

void CuttingStage::on_finish() {
  sim_->on_finish();
  for (sim::SampleObserver* o : downstream_) o->on_finish();
}

namespace {

const char* shape_name(ToolShape s) {
  return s == ToolShape::kFlat ? "flat" : s == ToolShape::kBall ? "ball" : "bull";
}

}  // namespace

std::string summary_json_with_cutting(const std::string& summary_json, const CuttingSimulator& sim,
                                      const CuttingConfig& config) {
  nlohmann::ordered_json j = nlohmann::ordered_json::parse(summary_json);
  const CuttingStats& s = sim.stats();
  nlohmann::ordered_json c;
  c["removed_mm3"] = s.removed_mm3;
  c["peak_mrr_mm3_s"] = s.peak_mrr_mm3_s;
  c["peak_load_pct"] = s.peak_load_pct;
  c["mean_load_pct"] = s.mean_load_pct();
  c["mean_cutting_load_pct"] = s.mean_cutting_load_pct();
  c["cutting_time_s"] = static_cast<double>(s.cutting_cycles) * sim.period_s();
  c["material"] = config.kc_n_mm2 > 0 ? std::string("kc_n_mm2") : config.material;
  c["kc_n_mm2"] = sim.kc_n_mm2();
  c["spindle_power_kw"] = config.spindle_power_kw;
  c["tool_changes"] = s.tool_changes;
  c["final_tool"] = sim.tool().number;
  c["cell_mm"] = sim.map().cell_mm();
  c["cells"] = {sim.map().nx(), sim.map().ny()};
  j["cutting"] = c;
  return j.dump(2) + "\n";
}

std::string format_cutting_summary(const CuttingSimulator& sim, const CuttingConfig& config) {
  const CuttingStats& s = sim.stats();
  std::string o;
  o += fmt::format("cutting       removed {:.0f} mm³, peak MRR {:.0f} mm³/s, cutting {:.3f} s\n",
                   s.removed_mm3, s.peak_mrr_mm3_s,
                   static_cast<double>(s.cutting_cycles) * sim.period_s());
  o += fmt::format(
      "cut load      peak {:.1f} %, mean {:.1f} % (while cutting {:.1f} %); kc {:g} N/mm² ({}), "
      "spindle {:g} kW\n",
      s.peak_load_pct, s.mean_load_pct(), s.mean_cutting_load_pct(), sim.kc_n_mm2(),
      config.kc_n_mm2 > 0 ? "cutting.kc_n_mm2" : config.material, config.spindle_power_kw);
  o += fmt::format("stock         {} x {} cells of {:g} mm; tool at the end T{} ({} Ø{:g})\n",
                   sim.map().nx(), sim.map().ny(), sim.map().cell_mm(), sim.tool().number,
                   shape_name(sim.tool().shape), sim.tool().diameter_mm);
  return o;
}

namespace {

// The height ramp of the map, u = 0 (stock bottom) … 1 (top): deep = dark blue, middle = teal,
// top = warm white.
double ramp_red(double u) {
  return u < 0.5 ? 20 + u * 2 * 40 : 60 + (u - 0.5) * 2 * 180;
}
double ramp_green(double u) {
  return u < 0.5 ? 30 + u * 2 * 120 : 150 + (u - 0.5) * 2 * 85;
}
double ramp_blue(double u) {
  return u < 0.5 ? 110 + u * 2 * 70 : 180 + (u - 0.5) * 2 * 30;
}

}  // namespace

std::array<unsigned char, 3> heightmap_colour(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return {static_cast<unsigned char>(ramp_red(u)), static_cast<unsigned char>(ramp_green(u)),
          static_cast<unsigned char>(ramp_blue(u))};
}

std::string heightmap_png(const HeightMap& map) {
  // At most 4096 pixels a side: larger maps are shown by the lowest cell of each k×k block,
  // so every cut stays visible.
  const std::size_t k = std::max<std::size_t>(1, (std::max(map.nx(), map.ny()) + 4095) / 4096);
  const std::size_t w = (map.nx() + k - 1) / k, h = (map.ny() + k - 1) / k;
  std::vector<float> z(w * h, std::numeric_limits<float>::infinity());
  for (std::size_t j = 0; j < map.ny(); ++j) {
    for (std::size_t i = 0; i < map.nx(); ++i) {
      float& c = z[(j / k) * w + i / k];
      c = std::min(c, map.at(i, j));
    }
  }
  const double lo = map.bottom_z_mm(), hi = map.top_z_mm();
  const double span = hi > lo ? hi - lo : 1;
  const double pix_mm = map.cell_mm() * static_cast<double>(k);
  // Light from the north-west, 45° up: L = (−1, 1, √2)/2.
  const double lx = -0.5, ly = 0.5, lz = std::sqrt(2.0) / 2;
  std::vector<unsigned char> rgb(w * h * 3);
  for (std::size_t row = 0; row < h; ++row) {
    const std::size_t j = h - 1 - row;  // image row 0 is the highest Y
    for (std::size_t i = 0; i < w; ++i) {
      const auto at = [&](std::size_t ii, std::size_t jj) {
        return static_cast<double>(z[jj * w + ii]);
      };
      const double gx = (at(std::min(i + 1, w - 1), j) - at(i > 0 ? i - 1 : 0, j)) / (2 * pix_mm);
      const double gy = (at(i, std::min(j + 1, h - 1)) - at(i, j > 0 ? j - 1 : 0)) / (2 * pix_mm);
      const double nlen = std::sqrt(gx * gx + gy * gy + 1);
      const double lambert = std::max(0.0, (-gx * lx - gy * ly + lz) / nlen);
      const double shade = std::clamp(0.35 + 0.65 * lambert / lz, 0.0, 1.15);
      const double u = std::clamp((at(i, j) - lo) / span, 0.0, 1.0);
      const double r = ramp_red(u), g = ramp_green(u), b = ramp_blue(u);
      unsigned char* px = &rgb[(row * w + i) * 3];
      px[0] = static_cast<unsigned char>(std::clamp(r * shade, 0.0, 255.0));
      px[1] = static_cast<unsigned char>(std::clamp(g * shade, 0.0, 255.0));
      px[2] = static_cast<unsigned char>(std::clamp(b * shade, 0.0, 255.0));
    }
  }
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(w);
  image.height = static_cast<png_uint_32>(h);
  image.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  const auto stride = static_cast<png_int_32>(w * 3);
  if (png_image_write_to_memory(&image, nullptr, &size, 0, rgb.data(), stride, nullptr) == 0) {
    throw std::runtime_error(std::string("PNG encoding failed: ") + image.message);
  }
  std::string out(size, '\0');
  if (png_image_write_to_memory(&image, out.data(), &size, 0, rgb.data(), stride, nullptr) == 0) {
    throw std::runtime_error(std::string("PNG encoding failed: ") + image.message);
  }
  out.resize(size);
  return out;
}

std::string heightmap_grid(const HeightMap& map, bool csv) {
  std::string out;
  if (csv) {
    out += fmt::format(
        "# cncore height map: x0_mm={} y0_mm={} cell_mm={} nx={} ny={} bottom_mm={} top_mm={}\n"
        "# one row per Y (lowest first), one height (mm) per X; cell centres at "
        "x0 + (i + 0.5)*cell, y0 + (j + 0.5)*cell\n",
        map.x0_mm(), map.y0_mm(), map.cell_mm(), map.nx(), map.ny(), map.bottom_z_mm(),
        map.top_z_mm());
    out.reserve(out.size() + map.nx() * map.ny() * 9);
    for (std::size_t j = 0; j < map.ny(); ++j) {
      for (std::size_t i = 0; i < map.nx(); ++i) {
        if (i > 0) out += ',';
        fmt::format_to(std::back_inserter(out), "{:.4f}", map.at(i, j));
      }
      out += '\n';
    }
    return out;
  }
  const auto put = [&out](const void* p, std::size_t n) {
    out.append(static_cast<const char*>(p), n);
  };
  out = "CNCZMAP1";
  const auto nx = static_cast<std::uint32_t>(map.nx()), ny = static_cast<std::uint32_t>(map.ny());
  const double geo[3] = {map.x0_mm(), map.y0_mm(), map.cell_mm()};
  put(&nx, 4);
  put(&ny, 4);
  put(geo, sizeof geo);
  put(map.heights().data(), map.heights().size() * sizeof(float));
  return out;
}

}  // namespace cncore::cut
