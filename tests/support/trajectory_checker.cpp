#include "trajectory_checker.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <sstream>

namespace cncore::testing {

const char* property_name(Property p) {
  switch (p) {
    case Property::kPath:
      return "P1 path";
    case Property::kSpeed:
      return "P2 speed";
    case Property::kJointSpeed:
      return "P2 joint speed";
    case Property::kAxisSpeed:
      return "P2 axis speed";
    case Property::kTangentialAccel:
      return "P3 tangential accel";
    case Property::kNormalAccel:
      return "P3 normal accel";
    case Property::kAxisAccel:
      return "P3 axis accel";
    case Property::kResultantAccel:
      return "P3 resultant accel";
    case Property::kJerk:
      return "P3 jerk";
    case Property::kEndPoint:
      return "P4 end point";
    case Property::kEndSpeed:
      return "P4 speed at stop";
    case Property::kStopPoint:
      return "P4 stop point";
    case Property::kCount:
      break;
  }
  return "?";
}

std::string Violation::to_string() const {
  std::ostringstream o;
  o.precision(6);
  o << property_name(property) << ": sample " << index << " t=" << t_s << " s line " << line;
  if (axis >= 0) o << " axis " << kAxisLetters[static_cast<std::size_t>(axis)];
  o << ": " << value << " > " << limit;
  return o.str();
}

std::string CheckReport::summary() const {
  std::ostringstream o;
  o.precision(6);
  o << samples << " samples, " << duration_s << " s, path " << path_length_mm
    << " mm; max: path error " << max_path_error_mm << " mm, speed " << max_speed_mm_s << " mm/s ("
    << max_speed_ratio << " of limit), tangential " << max_tangential_accel_mm_s2 << ", normal "
    << max_normal_accel_mm_s2 << ", resultant " << max_resultant_accel_mm_s2
    << " mm/s2, tangential jerk " << max_tangential_jerk_mm_s3 << " mm/s3, direction change "
    << max_direction_change_deg << " deg/cycle; end error " << end_error_mm << " mm, end speed "
    << end_speed_mm_s << " mm/s\n";
  for (std::size_t p = 0; p < counts.size(); ++p) {
    if (counts[p] == 0) continue;
    o << "  " << property_name(static_cast<Property>(p)) << ": " << counts[p] << " violations\n";
    int shown = 0;
    for (const auto& v : violations) {
      if (static_cast<std::size_t>(v.property) != p) continue;
      o << "    " << v.to_string() << "\n";
      if (++shown == 5) break;
    }
  }
  return o.str();
}

CheckReport check_trajectory(const Trajectory& tr, const std::vector<Block>& blocks,
                             const Limits& limits) {
  return check_trajectory(tr, build_path(blocks), limits);
}

namespace {

struct Projection {
  std::size_t seg = 0;
  double u = 0;
  double s = 0;     // XYZ path length from the start
  double dist = 0;  // distance to the path, all axes
};

double dist_axes(const AxisVec& a, const AxisVec& b) {
  double s = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s);
}

}  // namespace

CheckReport check_trajectory(const Trajectory& tr, const Path& path, const Limits& lim) {
  CheckReport rep;
  const std::size_t n = tr.size();
  rep.samples = n;
  rep.path_length_mm = path.length_mm;
  if (n == 0) return rep;
  rep.duration_s = tr.t_s.back() - tr.t_s.front();
  const double tau = lim.period_s > 0 ? lim.period_s : tr.period_s;
  const double m1 = 1 + lim.margin;
  // Rounding of the data (CSV decimals): every slack grows with it, and so do the tolerances
  // that are below it (an end point printed with 6 decimals cannot be checked to 1e-9 mm).
  const double q = std::max(lim.position_resolution_mm, tr.position_resolution_mm);
  // Each coordinate is off by up to q; a distance over 3 axes by up to √3·q < 3q, a first
  // difference by 2·(3q)... kept simple and generous: positions 3q, speed 4q/τ, acceleration
  // 8q/τ², jerk 16q/τ³.
  const double eps_p = 3 * q;
  const double eps_v = 4 * q / tau;
  const double eps_a = 8 * q / (tau * tau);
  const double eps_j = 16 * q / (tau * tau * tau);
  const double amax = lim.max_accel_mm_s2;
  const auto& segs = path.segments;
  const std::size_t nseg = segs.size();

  auto line_of = [&](std::size_t k, std::size_t seg) -> std::uint32_t {
    if (k < tr.line.size() && tr.line[k] != 0) return tr.line[k];
    return nseg > 0 ? segs[std::min(seg, nseg - 1)].line : 0;
  };
  std::vector<Projection> proj(n);
  auto add = [&](Property p, std::size_t k, double value, double limit, int axis = -1) {
    auto& c = rep.counts[static_cast<std::size_t>(p)];
    if (c < CheckReport::kMaxStoredPerProperty) {
      rep.violations.push_back({p, k, k < n ? tr.t_s[k] : 0.0,
                                line_of(k, proj[std::min(k, n - 1)].seg), value, limit, axis});
    }
    ++c;
  };

  // ---- Projection of every sample onto the path, walking forward only. ----
  // First segment within `snap` wins (the data is on the path up to its rounding); kept tight so
  // that a nearby leg of a hairpin is not taken for the segment the tool is on.
  const double snap = 1e-7 + 4 * q;
  // Samples this close to the path move along it: their speed is the progress of their
  // projections (a step across a corner is longer than its chord). Without the post filter up
  // to the P1 bound (1 µm): a tool on a merged chord (planner/line_merge.hpp) is nm off the
  // pieces it replaces, and its chord across a real corner faked a 0.6 % tangential
  // acceleration (1 nm before). With it, every step is measured by its chord (see v below).
  const double p1_mm = lim.path_tolerance_mm <= 1e-3 ? lim.path_tolerance_mm : 0.0;
  const double on_path = std::max({1e-6, 10 * q, p1_mm});
  const double vcap_mm_s = std::max(lim.max_feed_mm_min, lim.rapid_mm_min) / 60.0 *
                           std::max(1.0, lim.max_override_pct / 100.0);
  constexpr std::size_t kMaxScan = 200000;
  // One sample's projection, scanning forward from (cur, cur_u). `alternatives` (may be null)
  // receives later segments that also hold the sample within the snap distance.
  auto project_one = [&](std::size_t k, std::size_t cur, double cur_u, double cur_s,
                         std::vector<Projection>* alternatives) {
    const AxisVec& p = tr.pos[k];
    const double chord = k > 0 ? dist_axes(p, tr.pos[k - 1]) : 0.0;
    const double reach = 4 * chord + 2 * vcap_mm_s * tau + 10 * lim.path_tolerance_mm + 1e-6;
    Projection best{cur, cur_u, cur_s, std::numeric_limits<double>::infinity()};
    bool hit = false;
    std::size_t j = cur;
    for (std::size_t scanned = 0; j < nseg && scanned < kMaxScan; ++j, ++scanned) {
      if (j > cur && segs[j].s0_mm - cur_s > reach) break;
      double d = 0;
      const double u = segs[j].project(p, j == cur ? cur_u : 0.0, d);
      if (d < best.dist) best = {j, u, segs[j].s0_mm + u * segs[j].length_mm, d};
      if (d <= snap) {
        hit = true;
        break;
      }
    }
    if (hit) {
      // A later segment may be nearer still (e.g. right at a joint): look a little further.
      // Within one cycle's travel, a later segment through the same point (a reversal folds
      // the path onto itself) is an alternative reading of the sample.
      const double s_hit = best.s;
      const double horizon = s_hit + 2 * best.dist + 1e-12;
      const double fold_horizon = s_hit + 2 * vcap_mm_s * tau + snap;
      for (std::size_t j2 = j + 1; j2 < nseg && j2 < j + 64; ++j2) {
        if (segs[j2].s0_mm > std::max(horizon, alternatives ? fold_horizon : horizon)) break;
        double d = 0;
        const double u = segs[j2].project(p, 0.0, d);
        const Projection c{j2, u, segs[j2].s0_mm + u * segs[j2].length_mm, d};
        if (d < best.dist && segs[j2].s0_mm <= horizon) {
          best = c;
        } else if (alternatives && d <= snap) {
          alternatives->push_back(c);
        }
      }
    } else {
      // Off the path (violation, or the post-interpolation filter): also allow a small step
      // back on the current segment so the distance is the true nearest one.
      const PathSegment& cs = segs[cur];
      const double back = 2 * lim.path_tolerance_mm + chord;
      const double len6 = std::max(dist_axes(cs.end, cs.start), cs.length_mm);
      const double umin = len6 > 0 ? std::max(0.0, cur_u - back / len6) : cur_u;
      double d = 0;
      const double u = cs.project(p, umin, d);
      if (d < best.dist) best = {cur, u, cs.s0_mm + u * cs.length_mm, d};
    }
    return best;
  };
  if (nseg > 0) {
    std::size_t cur = 0;
    double cur_u = 0;
    double cur_s = 0;
    std::vector<Projection> alternatives;
    for (std::size_t k = 0; k < n; ++k) {
      alternatives.clear();
      Projection best = project_one(k, cur, cur_u, cur_s, &alternatives);
      if (!alternatives.empty() && k + 1 < n) {
        // Positions alone cannot tell a sample on a fold of the path from one just past it.
        // Take the reading that needs the lowest speed over the two cycles around the sample
        // (the servo set-points are consistent with it), so a reversal passed at v is not
        // charged 2v; a real overspeed shows in every reading.
        const double s_prev = k > 0 ? proj[k - 1].s : 0.0;
        auto cost = [&](const Projection& c) {
          const Projection nx = project_one(k + 1, c.seg, c.u, c.s, nullptr);
          return std::max(c.s - s_prev, nx.s - c.s);
        };
        double best_cost = cost(best);
        for (const Projection& c : alternatives) {
          const double cc = cost(c);
          if (cc < best_cost) {
            best_cost = cc;
            best = c;
          }
        }
      }
      proj[k] = best;
      cur = best.seg;
      cur_u = best.u;
      cur_s = best.s;
    }
  }

  // ---- Path speed per cycle. ----
  std::vector<double> v(n, 0.0);
  std::vector<Vec3> d(n);  // XYZ chords
  for (std::size_t k = 1; k < n; ++k) {
    d[k] = tr.pos[k].xyz() - tr.pos[k - 1].xyz();
    // With the post filter the set-points leave the path by design (within the contour
    // tolerance) and the servos follow their chords: progress along the path would charge a
    // reversal that the filter turns short of its tip (at X 0.998 of a fold at 1.000) the skipped
    // 2·2 µm as speed.
    const bool along = lim.post_filter_s <= 0 && nseg > 0 && proj[k].dist <= on_path &&
                       proj[k - 1].dist <= on_path;
    v[k] = along ? std::max(0.0, proj[k].s - proj[k - 1].s) / tau : norm(d[k]) / tau;
  }

  // ---- P1 ----
  if (nseg > 0) {
    for (std::size_t k = 0; k < n; ++k) {
      rep.max_path_error_mm = std::max(rep.max_path_error_mm, proj[k].dist);
      if (proj[k].dist > lim.path_tolerance_mm * m1 + eps_p)
        add(Property::kPath, k, proj[k].dist, lim.path_tolerance_mm);
    }
  }

  // ---- P2 path speed, with the override ramp allowance. ----
  // f_eff[k] = max over samples with t ≥ t[k] − ramp of override·correction (monotone deque).
  const double ramp = lim.ramp_s();
  std::vector<double> f_eff(n, 1.0);
  {
    std::deque<std::size_t> dq;
    auto f_at = [&](std::size_t k) {
      const double o = k < tr.override_pct.size() ? tr.override_pct[k] : 100.0;
      const double c = k < tr.correction.size() ? tr.correction[k] : 1.0;
      return o / 100.0 * c;
    };
    std::size_t lo = 0;
    for (std::size_t k = 0; k < n; ++k) {
      while (!dq.empty() && f_at(dq.back()) <= f_at(k)) dq.pop_back();
      dq.push_back(k);
      while (lo < k && tr.t_s[lo] < tr.t_s[k] - ramp - 1e-12) ++lo;
      while (dq.front() < lo) dq.pop_front();
      f_eff[k] = f_at(dq.front());
    }
  }
  auto shape_limit = [&](const PathSegment& sg) {
    double vb = sg.rapid ? lim.rapid_mm_s() : lim.feed_mm_s();
    if (sg.arc) vb = std::min(vb, std::sqrt(sg.radius_mm() * amax));
    return vb;
  };
  for (std::size_t k = 1; k < n; ++k) {
    rep.max_speed_mm_s = std::max(rep.max_speed_mm_s, v[k]);
    if (nseg == 0) continue;
    // A sample that lands exactly on the start of a segment arrived by the segment before: the
    // cycle moved on that one (a G0 ending where a slow G1 starts is not charged the G1's feed).
    std::size_t seg_k = proj[k].seg;
    if (seg_k > proj[k - 1].seg && proj[k].s - segs[seg_k].s0_mm <= snap) --seg_k;
    const PathSegment& sg = segs[seg_k];
    double limit = shape_limit(sg);
    if (sg.rapid) {
      if (lim.override_applies_to_rapid)
        limit = std::min(limit, lim.rapid_mm_s() * std::min(1.0, f_eff[k]));
    } else {
      const double f_mm_s = sg.feed_mm_min > 0 ? sg.feed_mm_min / 60.0 : lim.feed_mm_s();
      limit = std::min(limit, f_mm_s * f_eff[k]);
    }
    if (limit > 0) rep.max_speed_ratio = std::max(rep.max_speed_ratio, v[k] / limit);
    if (v[k] > limit * m1 + eps_v) add(Property::kSpeed, k, v[k], limit);
  }

  // ---- P2 at joints, P4 at stop points and the end. ----
  if (nseg > 0) {
    std::size_t k = 0;
    for (std::size_t j = 0; j < nseg; ++j) {
      // First sample at or past the end of segment j.
      // A stop point is reached by a sample within its tolerance; a plain joint by a sample at
      // it (within the snap distance) or on a later segment.
      const bool is_last = j + 1 == nseg;
      const double reach_tol =
          segs[j].stop_after ? (is_last ? lim.end_tolerance_mm : lim.stop_tolerance_mm) + eps_p
                             : snap;
      auto reached = [&](std::size_t kk) {
        // Near the end along the path too, not only in space: a full circle ends where it
        // starts, and an arc with extra turns passes its end point on every turn before it.
        // (u ≥ 0.5 as before, for segments shorter than the tolerance.)
        const double left_mm = (1 - proj[kk].u) * segs[j].length_mm;
        return proj[kk].seg > j ||
               (proj[kk].seg == j && proj[kk].u >= 0.5 && left_mm <= 2 * reach_tol + eps_p &&
                dist_axes(tr.pos[kk], segs[j].end) <= reach_tol);
      };
      while (k < n && !reached(k)) ++k;
      JointSpeed js;
      js.segment = j;
      js.stop = segs[j].stop_after;
      js.line = j + 1 < nseg ? segs[j + 1].line : segs[j].line;
      if (j + 1 < nseg) {
        const double theta = corner_angle_rad(segs[j], segs[j + 1]);
        js.angle_deg = theta * 180 / std::numbers::pi;
        double vg = std::min(shape_limit(segs[j]), shape_limit(segs[j + 1]));
        if (theta > 1e-12) vg = std::min(vg, amax * tau / (2 * std::sin(theta / 2)));
        js.vg_mm_s = vg;
      }
      if (js.stop) js.vg_mm_s = amax * tau;
      if (k >= n) {
        rep.joints.push_back(js);
        continue;
      }
      js.speed_mm_s = k > 0 ? v[k] : 0.0;
      if (js.stop) {
        const bool last = j + 1 == nseg;
        const double tol = last ? lim.end_tolerance_mm : lim.stop_tolerance_mm;
        const double err = dist_axes(tr.pos[k], segs[j].end);
        if (err > tol + eps_p) {
          add(Property::kStopPoint, k, err, tol);  // jumped over the stop point
        } else {
          if (js.speed_mm_s > js.vg_mm_s * m1 + eps_v)
            add(Property::kEndSpeed, k, js.speed_mm_s, js.vg_mm_s);
          if (segs[j].dwell_after_s > 0) {
            std::size_t e = k;
            while (e + 1 < n && dist_axes(tr.pos[e + 1], segs[j].end) <= tol + eps_p) ++e;
            const double stayed = tr.t_s[e] - tr.t_s[k];
            if (stayed < segs[j].dwell_after_s - tau - 1e-9)
              add(Property::kStopPoint, k, stayed, segs[j].dwell_after_s);
          }
        }
      } else if (js.speed_mm_s > js.vg_mm_s * m1 + eps_v) {
        add(Property::kJointSpeed, k, js.speed_mm_s, js.vg_mm_s);
      }
      rep.joints.push_back(js);
    }
    rep.end_error_mm = dist_axes(tr.pos.back(), path.end);
    rep.end_speed_mm_s = v[n - 1];
    if (rep.end_error_mm > lim.end_tolerance_mm + eps_p)
      add(Property::kEndPoint, n - 1, rep.end_error_mm, lim.end_tolerance_mm);
    const bool end_checked = !rep.joints.empty() && rep.joints.back().speed_mm_s >= 0;
    if (!end_checked && rep.end_speed_mm_s > amax * tau * m1 + eps_v)
      add(Property::kEndSpeed, n - 1, rep.end_speed_mm_s, amax * tau);
  }

  // ---- P2 per axis, P3. ----
  std::vector<double> at(n, 0.0);  // tangential acceleration at sample k
  for (std::size_t k = 1; k < n; ++k) {
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      const double va = std::abs(tr.pos[k][i] - tr.pos[k - 1][i]) / tau;
      rep.max_axis_speed_mm_s[i] = std::max(rep.max_axis_speed_mm_s[i], va);
      const double lv = lim.axis_speed_mm_min[i] / 60.0;
      if (lv > 0 && va > lv * m1 + eps_v) add(Property::kAxisSpeed, k, va, lv, static_cast<int>(i));
    }
    if (k + 1 >= n) continue;
    const double a_t = (v[k + 1] - v[k]) / tau;
    at[k] = a_t;
    rep.max_tangential_accel_mm_s2 = std::max(rep.max_tangential_accel_mm_s2, std::abs(a_t));
    if (std::abs(a_t) > amax * m1 + eps_a) add(Property::kTangentialAccel, k, std::abs(a_t), amax);
    const Vec3 d1 = d[k], d2 = d[k + 1];
    const double l1 = norm(d1), l2 = norm(d2);
    double a_n = 0;
    if (l1 > 0 && l2 > 0) {
      // 2·√(l1·l2)·sin(θ/2) = √(l1·l2)·|d̂2 − d̂1|
      a_n = std::sqrt(l1 * l2) * norm((1.0 / l2) * d2 - (1.0 / l1) * d1) / (tau * tau);
    }
    rep.max_normal_accel_mm_s2 = std::max(rep.max_normal_accel_mm_s2, a_n);
    if (l1 >= 1e-3 && l2 >= 1e-3 && l1 >= 10 * q && l2 >= 10 * q) {
      const double ang = std::atan2(norm(cross(d1, d2)), dot(d1, d2)) * 180 / std::numbers::pi;
      rep.max_direction_change_deg = std::max(rep.max_direction_change_deg, ang);
    }
    if (a_n > amax * m1 + eps_a) add(Property::kNormalAccel, k, a_n, amax);
    const double a_r = norm(d2 - d1) / (tau * tau);
    rep.max_resultant_accel_mm_s2 = std::max(rep.max_resultant_accel_mm_s2, a_r);
    if (lim.max_resultant_accel_mm_s2 > 0 && a_r > lim.max_resultant_accel_mm_s2 * m1 + eps_a)
      add(Property::kResultantAccel, k, a_r, lim.max_resultant_accel_mm_s2);
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      const double aa =
          std::abs(tr.pos[k + 1][i] - 2 * tr.pos[k][i] + tr.pos[k - 1][i]) / (tau * tau);
      rep.max_axis_accel_mm_s2[i] = std::max(rep.max_axis_accel_mm_s2[i], aa);
      const double la = lim.axis_accel_mm_s2[i];
      if (la > 0 && aa > la * m1 + eps_a) add(Property::kAxisAccel, k, aa, la, static_cast<int>(i));
    }
  }
  // Tangential jerk is a property of the speed along the path: a window of samples k−1 … k+2
  // that turns a corner (a joint with a direction change between its first and last sample, or
  // a sample off the path: a filter rounding a corner) measures the turn, which the normal and
  // per-axis acceleration bound, not the speed profile. Such windows are skipped. A post filter
  // of P cycles spreads the turn over P cycles on each side: the window grows by P.
  const std::size_t post_cycles =
      lim.post_filter_s > 0 ? static_cast<std::size_t>(std::ceil(lim.post_filter_s / tau)) : 0;
  auto turns_corner = [&](std::size_t k) {
    if (nseg == 0) return false;
    for (std::size_t i = k - 1; i <= k + 2; ++i) {
      if (proj[i].dist > on_path) return true;
    }
    const std::size_t lo = k - 1 >= post_cycles ? k - 1 - post_cycles : 0;
    const std::size_t hi = std::min(n - 1, k + 2 + post_cycles);
    for (std::size_t j = proj[lo].seg; j < proj[hi].seg && j + 1 < nseg; ++j) {
      if (corner_angle_rad(segs[j], segs[j + 1]) > 1e-9) return true;
    }
    return false;
  };
  for (std::size_t k = 1; k + 2 < n; ++k) {
    const double jt = std::abs(at[k + 1] - at[k]) / tau;
    if (!turns_corner(k)) {
      rep.max_tangential_jerk_mm_s3 = std::max(rep.max_tangential_jerk_mm_s3, jt);
      if (lim.check_jerk && lim.max_jerk_mm_s3 > 0 && jt > lim.max_jerk_mm_s3 * m1 + eps_j)
        add(Property::kJerk, k, jt, lim.max_jerk_mm_s3);
    }
    const Vec3 j3 = tr.pos[k + 2].xyz() - 3.0 * tr.pos[k + 1].xyz() + 3.0 * tr.pos[k].xyz() -
                    tr.pos[k - 1].xyz();
    rep.max_resultant_jerk_mm_s3 =
        std::max(rep.max_resultant_jerk_mm_s3, norm(j3) / (tau * tau * tau));
  }
  rep.speed_mm_s = std::move(v);
  return rep;
}

}  // namespace cncore::testing
