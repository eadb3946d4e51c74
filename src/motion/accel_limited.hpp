// The acceleration-limited acc/dec type before interpolation: the tool's path speed changes by
// at most the acceleration limit per cycle, every speed limit ahead is met by braking just in
// time, and there is no filter delay. The derivation is in comments at the top of the
// accel_limited*.cpp files (accel_limited.cpp lists which part is where); the numbers in the
// comments below (7., 9., …) are its sections.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "core/geometry.hpp"
#include "motion/accdec.hpp"
#include "motion/moving_average.hpp"
#include "planner/buffer.hpp"
#include "planner/huge_pages.hpp"
#include "planner/min_tree.hpp"
#include "planner/turn_window.hpp"

namespace cncore::motion {

class AccelLimitedAccDec final : public AccDec {
  // The per-slot and per-cap arrays and the trees (~4.7 MB for a 10 000-block window) come from
  // huge pages like the kernel's other buffers (planner/huge_pages.hpp: a faster construction).
  template <typename T>
  using Buf = std::vector<T, planner::HugePageAllocator<T>>;

 public:
  // check_reference_walk: every cycle also compute the bound by reference_bound() and count the
  // cycles where it differs (reference_mismatches(); tests).
  AccelLimitedAccDec(const planner::SegmentBuffer& buffer, const planner::Limits& limits,
                     double or_max, bool check_reference_walk = false);

  // The kernel computed planner::joint_speed_pc(item index_a, the next segment, limits, false)
  // for the joint the next on_segment() closes, and the directions there (a's end, b's start):
  // joint_zones() takes them instead of computing the same doubles again (a per-block cost of
  // fine programs).
  // `turn`: the path's turn over the cycle before the joint at corner_pc (a chain of short
  // segments, planner/turn_window.hpp), which the joint's zone must leave room for (7.).
  void set_next_corner(std::uint64_t index_a, double corner_pc, const AxisVec& a_end,
                       const AxisVec& b_start, const planner::Turn& turn = {}) {
    corner_index_a_ = index_a;
    corner_pc_ = corner_pc;
    corner_e_ = a_end;
    corner_s_ = b_start;
    corner_turn_ = turn;
  }
  void on_segment(std::uint64_t index, const planner::Segment& s) override;
  void on_joint(std::uint64_t index_a, const planner::Segment& a,
                const planner::Segment& b) override;
  bool holds(std::uint64_t index) const override {
    const std::size_t s = 3 * buf_.slot(index);
    return owner_[s] != kNone || owner_[s + 1] != kNone || owner_[s + 2] != kNone;
  }
  void on_retire(std::uint64_t index) override;
  bool detach(std::uint64_t index) override;
  void step(const CycleInput& in) override;
  // A stop requested at a block end (accel_limited_late.cpp, 14.).
  double stop_reach_mm() override;
  bool can_stop_at(double stop_mm) const override;

  // With a jerk stage (T2 > 1) the tool follows the commanded position through a moving
  // average of T2 cycles (8.); without one it is the commanded position.
  double tool_mm() const override { return tool_mm_; }
  double tool_speed_pc() const override { return tool_step_; }
  double commanded_mm() const override { return pos_mm_; }
  bool at_rest() const override { return step_ == 0 && jerk_.at_rest(); }

  // The plain minimum over every live cap, by a walk (O(n); tests compare it with the trees).
  double reference_bound(double or_ratio) const;
  // The bound of the last cycle, min(geometric caps, feed caps); maintained with
  // check_reference_walk only (step() leaves out the braking bounds that cannot bind).
  double last_bound() const { return last_bound_; }
  std::uint64_t reference_mismatches() const { return mismatches_; }
  // Acceleration used by this type along the segment in buffer slot of `index` (mm/cycle²).
  double segment_accel_pc2(std::uint64_t index) const;

 private:
  // A cap: the speed limit V (mm/cycle; feed caps: F at 100 % override) holds for every cycle
  // whose step starts in [c, e) and for every step that lands at or after c.
  struct Cap {
    double c_mm = 0, e_mm = 0;
    double v = 0;
    double sigma_c = 0;  // σ(c) (see the derivation)
    bool feed = false;
    bool lattice = false;  // braking key in the exact discrete (lattice) form, see 3.
    double entry = 0;      // where it takes over from its key (entry_mm(), set by insert())
  };
  enum class State : std::uint8_t { kEmpty, kApproaching, kActive };

  // Caps live in pools (one per kind: segment speed, feed, joint), ids g = kind·pool_ + i; the
  // trees are indexed by g. A cap *position* p = 3·slot + kind (3·capacity + kind: overflow)
  // names the buffer slot that holds it (holds()); owner_[p] = g, where_[g] = p. Extending a
  // cap to the next segment moves its position only: no tree update while it approaches.
  static constexpr std::uint32_t kNone = ~std::uint32_t{0};
  void insert(std::size_t pos, const Cap& cap);
  void insert_joint_cap(std::size_t slot_a, std::size_t slot_b, double joint_mm, double len_a,
                        double vg);
  void activate(std::size_t g);
  void set_keys(std::size_t g, double entry);
  void clear_keys(std::size_t g);
  double entry_mm(const Cap& cap) const;
  // The lowest path position from the tool's segment on where σ reaches `target`, for a
  // target ≤ σ(hint_mm); `slot`: the buffer slot of the segment it lies in (capacity: none).
  double mm_at_sigma(double target, double hint_mm, std::size_t& slot) const;
  void clear(std::size_t pos);
  // Moves the cap at position `from` to the empty position `to` (same kind).
  void move(std::size_t from, std::size_t to);
  State pos_state(std::size_t pos) const {
    return owner_[pos] == kNone ? State::kEmpty : state_[owner_[pos]];
  }
  // The lowest r of the buffer item `index` as a whole (segments strictly inside a span of
  // r_span), with its joint zones: leaves of r_zone_ (events: empty).
  void update_r(std::uint64_t index);
  double sigma_at(double pos_mm) const;  // σ of a path position inside the buffer
  // ∫ r over the first x mm of the segment in `slot` (head and tail zones included).
  double seg_sigma(std::size_t slot, double x_mm) const;
  // The lowest r over path positions [from, to] (the current segment and the following ones),
  // with the joint zones.
  // skip (optional): in, the hint's distance from the tool's item for the search of to_mm's
  // item; out, that item's distance.
  double r_span(double from_mm, double to_mm, std::uint64_t* skip = nullptr) const;
  // A joint a → b without a stop between: the acceleration zones on both sides (see 7.).
  void joint_zones(std::uint64_t index_a, std::size_t slot_b, const planner::Segment& b);
  void advance_current();
  // The cycle after the tool crossed a capped joint between two lines (9.): the exact limit of
  // this cycle's step from the second difference around the crossing (kInf: none; the joint cap
  // then stays). Clears the joint cap when it returns a limit.
  double after_corner();
  double pair_rise(const planner::Segment& s) const;
  // 11. Centred corners: the joint (j, Vg, the cap's c), the directions and their cosine, and
  // the highest r from the tool up to j.
  struct Centre {
    double vg = 0, j = 0, c_mm = 0, c = 0, r_hi = 1, r_lo = 1;
    std::size_t slot_a = 0;  // a's buffer slot, and its start
    double a_s0 = 0;
    AxisVec e, sd;
  };
  // The slowest step the cycle after a step [from, to] on the line in `slot` (start s0) can be
  // made to take is that step less ρ·A0 (11.): ρ = the larger of the mean r over the step and
  // the r of the piece at `to`.
  double slowdown_r(std::size_t slot, double s0, double from_mm, double to_mm) const;
  // The r of the piece of the segment in `slot` at x mm from its start, as r_span() takes it for
  // a span starting there (≥ the r of a step's reach from there: what a hold slows by).
  double piece_r(std::size_t slot, double x_mm) const;
  bool centre_setup(std::size_t g, const planner::Segment& a, const planner::Segment& b,
                    Centre& ct) const;
  // The step u0 from from_mm lands in [c, j) and its sample keeps every limit for each crossing
  // step the next cycle may take.
  bool centred_ok(const Centre& ct, double from_mm, double u0) const;
  // The largest x meeting every per-axis limit |(k_e·E_i + k_s·S_i)·x + m_e·E_i + m_s·S_i| ≤ a_i.
  double centred_top(const Centre& ct, double k_e, double k_s, double m_e, double m_s) const;
  // The largest feasible step in (u, hi] (u when none).
  double centred_step(const Centre& ct, double u, double hi) const;
  // The largest step in (u, hi] after which the slowest next step is a feasible centred one
  // (lo_next); u when none.
  double committing_step(const Centre& ct, double u, double hi, double& lo_next) const;
  // A committing step was taken: the next cycle (from from_mm) takes a centred step ≥ lo.
  struct Commit {
    bool valid = false;
    double j_mm = 0, from_mm = 0, lo = 0;
  } commit_;
  // Lowers r over the first `mm` of the segment in `slot` to at most `r` (head zone), and σ's r
  // for decreases to at most `r_dec` (≥ r).
  void add_head(std::size_t slot, double mm, double r, double r_dec);
  // A head zone that reaches past the segment it starts in (8.): r ≤ `r` up to path position
  // `until_mm`, applied to each later segment as it arrives.
  void carry(double until_mm, double r);
  struct Bounds {
    double geo, feed;
  };
  Bounds bound(double or_ratio, double sigma_p) const;
  // The braking bound of a key K at σ_p, √(A0² + K − 2·A0·σ_p) − A0, and of a lattice key,
  // max(0, √(K − 2·A0·σ_p) − A0/2) (3.).
  double brake(double k, double sigma_p) const;
  double lattice(double k, double sigma_p) const;
  // The feed part of bound(), the same double.
  double feed_bound(double or_ratio, double sigma_p) const;
  // On the tool's arc (slot), the largest step that can still meet the approaching caps when
  // braking with what the speed leaves of the axis budget (10.); 0 when it does not apply.
  // (feed: the feed keys of the override level; else the geometric and lattice keys.)
  // `at`: where the curve ends (e, σ(e)) and the target there (W).
  struct ArcTarget {
    double e_mm = 0, sigma_e = 0, w = 0;
  };
  double arc_brake_step(std::size_t slot, const planner::Segment& arc, double or_ratio, bool feed,
                        ArcTarget& at) const;
  // The override level whose feed keys the cycle reads (cached for the last override).
  std::size_t level_of(double or_ratio) const;

  const planner::SegmentBuffer& buf_;
  planner::Limits lim_;
  double tail_cap_pc_ = 0;  // V_t: speed of the last V_t mm before a stop
  double a0_;               // A0: the path acceleration limit (mm/cycle²)
  double or_max_;
  double level_step_;  // override levels of the feed-cap key trees
  std::size_t levels_;
  mutable double level_or_ = std::numeric_limits<double>::quiet_NaN();
  mutable std::size_t level_ = 0;

  // Per buffer slot: σ at the segment start, acceleration ratio r = A_seg/A0, speed cap.
  Buf<double> sigma0_, ratio_, vcap_;
  // Per buffer slot: the joint zones (see 7.): r ≤ head_r_ on the first head_mm_, ≤ tail_r_ on
  // the last tail_mm_ of the segment (r_span(): speed increases, holds, the stops' landing);
  // head_rd_ and tail_rd_ ≥ them are the zones' r for decreases (σ, the braking bounds).
  Buf<double> len_mm_, head_mm_, head_r_, tail_mm_, tail_r_, head_rd_, tail_rd_;
  Buf<double> s0_mm_;  // the segment's s0_mm (r_span() reads it without the Segment)
  // Per buffer slot, σ over the segment as pieces [0, p1), [p1, p2), [p2, len] of rates
  // rate0..2 and σ sig1, sig2 at p1, p2 (no zone: p1 = 0, p2 = len), from len, r and the zones
  // by refresh_pieces() whenever one of them changes: seg_sigma() of every cycle reads one
  // cache line instead of six arrays. 64 bytes.
  struct SigmaPieces {
    double len, p1, p2, sig1, sig2, rate0, rate1, rate2;
  };
  Buf<SigmaPieces> pieces_;
  void refresh_pieces(std::size_t slot);
  // Per buffer slot, arcs whose plane axes share normal and tangential acceleration: the axis
  // bound g (0: none), the radius of curvature, and the ratio of the linear axis shares alone —
  // an override decrease decelerates with what the current speed leaves (5.).
  Buf<double> arc_g_, arc_rho_, lin_r_;
  // Passing speed the joint zones of the joint after item zone_index_a_ were computed for (a
  // joint cap when lower than the segments' caps; see 7.).
  double zone_vg_ = 0;
  // The running square of what the caps before can leave at the last joint (joint_zones()).
  double reach_sq_ = std::numeric_limits<double>::infinity();
  std::uint64_t reach_b_ = ~std::uint64_t{0};  // the segment after that joint
  double zone_joint_pc_ = 0;  // planner::joint_speed_pc of that joint (on_joint reuses it)
  // The directions at that joint (a's end, b's start) and at a's start (on_joint reuses them).
  AxisVec zone_e_, zone_s_, zone_a_start_;
  // The cap of a chain of corners ending there (both joints), where its zone's floor needs one.
  double zone_chain_vg_ = std::numeric_limits<double>::infinity();
  std::uint64_t zone_index_a_ = ~std::uint64_t{0};
  std::uint64_t corner_index_a_ = ~std::uint64_t{0};  // set_next_corner()
  double corner_pc_ = 0;
  AxisVec corner_e_, corner_s_;
  planner::Turn corner_turn_;
  double sigma_total_ = 0;

  // Caps: three positions per buffer slot (range cap of the segment's speed, of its feed, the
  // cap of the joint at its start), each holding at most one cap of its kind, so a pool of
  // capacity + 1 ids per kind (the overflow position included) never runs out.
  std::size_t pool_;
  Buf<Cap> caps_;     // by id g (huge pages: 1.2 MB on 4 KB pages was ~300 faults per kernel)
  Buf<State> state_;  // by id g
  Buf<std::uint32_t> owner_, where_;
  Buf<std::uint32_t> free_;  // free ids per kind: free_[kind·pool_ + k], k < free_n_
  std::array<std::size_t, 3> free_n_{};
  planner::MinTree entry_, key_geo_, key_lattice_, active_geo_, active_feed_, release_;
  // One tree per override level (levels_ ≤ kMaxLevels), over the feed pool's ids (g − pool_).
  // Its leaves are not stored: feed_v_[i] (V of an approaching feed cap) and feed_k_[i]
  // (2·A0·σ(c); kInf: no key) give leaf i's key at level j, feed_key(); update_feed_group()
  // hands the tree a group's minima.
  static constexpr std::size_t kMaxLevels = 41;
  planner::MinTreeGroups key_feed_;
  Buf<double> feed_v_, feed_k_;
  double feed_key(std::size_t i, std::size_t level) const {
    const double v = static_cast<double>(level) * level_step_ * feed_v_[i];
    return v * v + feed_k_[i];
  }
  void update_feed_group(std::size_t i);
  // Positions 3·(capacity + i) + k (k = 0, 1, 2; i < kOverflow): active caps of retired
  // segments (detach()).
  static constexpr std::size_t kOverflow = 8;
  std::size_t overflow_;
  planner::MinTree r_zone_;  // by buffer slot, see update_r()

  // Range caps of the previous segment (to extend them instead of adding a cap per segment).
  bool have_prev_ = false;
  std::uint64_t prev_index_ = 0;
  double prev_end_mm_ = 0;

  // The previous joint (x → a), for two or three corners within one cycle.
  struct PrevJoint {
    bool valid = false;
    std::uint64_t index_a = 0, index_b = 0;
    AxisVec end_dir;   // direction at the end of x
    AxisVec end_dir2;  // direction at the end of the segment before x
    double vg = 0;
    double vg2 = 0;
    bool short_a = false;
    // The segment a (x for the joint after it): start direction, length, sweep (7.'s chains).
    AxisVec a_start_dir;
    double a_len_mm = 0, a_sweep_rad = 0;
  } prev_;
  // The zone of the last joint (7.), where 13. may size it again for the speed the next joint's
  // cap leaves there: only a plain one (two lines, no chain, no filter, inside a and b).
  // Its tail may reach back over a few segments before a (walk[0] = a, then back): their tail
  // zones as they were before it, restored when it is sized again.
  static constexpr std::size_t kRezoneWalk = 4;
  struct WalkedTail {
    std::uint64_t index = 0;
    double mm = 0, r = 1, rd = 1;
  };
  struct LastZone {
    bool valid = false;
    std::uint64_t index_a = 0;
    double j_mm = 0, v = 0, r_hi = 1, r_top = 1, floor = 0;
    AxisVec e, s;
    std::array<WalkedTail, kRezoneWalk> walk{};
    std::size_t n_walk = 0;
    double chain_mm = 0;  // a chain's middle (7.; 0: none): the zone reached back over it too
  } last_zone_;
  // 13.: the zone of the joint before `index_a` sized again for the cap vc of the joint at its
  // end (true: changed).
  bool rezone_before(const LastZone& z, std::uint64_t index_b, double vc);
  double plain_zone_d(const AxisVec& e, const AxisVec& s, double r_hi, double v,
                      bool decreases_only) const;
  void resigma(std::uint64_t first, std::uint64_t index_a);

  // The last step left the line under the tool at its end j_mm (direction e there): 9.
  struct Crossed {
    bool valid = false;
    double j_mm = 0, from_mm = 0, sigma_from = 0;  // (σ at from_mm)
    AxisVec e;
  } crossed_;

  std::uint64_t cur_ = 0;         // buffer item under the tool
  std::uint64_t cur_skip_ = 0;    // items advance_current() skipped when it last left an item
  std::uint64_t reach_skip_ = 0;  // items from cur_ to the item of the last step's reach
  double pos_mm_ = 0, step_ = 0, last_bound_ = 0;
  double prev_sigma_ = 0;  // σ where the last step started
  double cached_stop_mm_ = -1, cached_stop_sigma_ = 0;
  double prev_or_ = 0;         // the override of the last cycle
  bool feed_recover_ = false;  // lowered override: above the feed limit, decelerating to it
  bool check_ = false;
  std::uint64_t mismatches_ = 0;

  // Jerk stage and post filter (8.): the output averages the commanded steps over lag_ cycles
  // at most; a cap reaches cap_lag_·V further on both sides, a zone or a carried r
  // reach_lag_·V.
  MovingAverage jerk_;
  bool jerk_on_ = false;
  double lag_ = 0;
  double reach_lag_ = 0;  // (T2 + 1)/2 + Tp
  double cap_lag_ = 0;    // (T2 − 1)/2 + Tp
  double tool_mm_ = 0, tool_step_ = 0;
  double vtop_pc_ = 0;  // the highest step any segment so far allows (the r carry's reach)
  struct Carry {
    double until_mm = 0, r = 1;
  };
  static constexpr std::size_t kCarries = 8;
  std::array<Carry, kCarries> carries_{};
  std::size_t n_carries_ = 0;

  // Late blocks (6., 8.): a block one of whose caps would bind at once is held: the tool stops
  // at hold_mm_ (the window's end it was braking for) and settles, and only then do the caps of
  // the blocks that arrived meanwhile (pending_, in arrival order) take effect.
  bool late_hold_ = false;
  bool held_cycle_ = false;  // step() runs again with hold_mm_ as the stop
  double hold_mm_ = 0;
  std::uint32_t rest_cycles_ = 0;  // cycles in a row that started with the tool at rest
  std::vector<double> recent_;     // the commanded steps of the last lag_ cycles (ring)
  std::size_t recent_pos_ = 0;
  std::vector<std::pair<std::size_t, Cap>> pending_;
  // Set by on_segment() when the commanded position is near enough to the new block's start for
  // one of its caps to bind at once: the last cycle's σ and the largest recent step.
  bool late_check_ = false;
  double late_sigma_p_ = 0, late_m_ = 0, late_at_mm_ = 0;
  Cap late_range_[2];  // the new block's range caps that are not extensions of earlier ones
  std::size_t n_late_range_ = 0;
  // The last step relied on 10. (above the braking bounds of the keys): that curve's e and
  // σ(e), and the W of the keys it was taken for (kInf: not relied on). A late block whose caps
  // move e back or lower W is held (6.).
  double relied_e_mm_ = std::numeric_limits<double>::infinity(), relied_sigma_e_ = 0;
  double relied_w_geo_ = std::numeric_limits<double>::infinity();
  double relied_w_feed_ = std::numeric_limits<double>::infinity();
  bool late_cap(const Cap& cap) const;
  // Tests late_range_ and the joint's cap (null: none); zone_r < 1: a joint zone of that rate
  // will cover [zone_mm, at_mm] (7.), which lowers σ there, and re-key the approaching caps of
  // the segments it reaches back over (index_a and up to kZoneWalk before it).
  void check_late(double at_mm, double zone_mm, double zone_r, const Cap* joint_cap,
                  std::uint64_t index_a = 0);
  bool rekeying_ = false;         // joint_zones() re-keys caps: insert() applies them at once
  bool releasing_ = false;        // release_hold() inserts pending caps
  std::size_t pending_next_ = 0;  // the first pending cap not yet inserted
  // Holds a late block when the stop's landing bounds at stop_mm, with r_new over the block
  // (from at_mm), would fall below the last step (6.).
  void check_stop(double stop_mm, double at_mm, double r_new);
  // The step a requested stop must leave room for (14.): the last one and two more A0.
  double request_step() const;
  void start_hold(double at_mm);
  void release_hold();
};

}  // namespace cncore::motion
