// The jerk-aware lower bound: the shortest time along the same path with the same speed caps as
// the acceleration bound (bound.hpp) and, besides |a| ≤ Amax, |jerk| ≤ Jmax along the path
// (a, jerk: the first and second time derivatives of the path speed).
//
// Input: the acceleration bound's speed envelope E(s), one piece per Seg:
//   E(x) = min(cap, √(u0² + 2·a·x), √(u1² + 2·d·(L − x)))   on a piece of length L,
// an upper bound of the speed at s of every trajectory within the acceleration limits, so of
// every jerk-limited one too; ∫ds/E is the acceleration bound's time.
//
// Windows. E is monotone between consecutive entries of u0, max of piece 0, u1, max of piece 1,
// …; the path is cut at the local maxima of E ("peaks"), so in each window W = [P0, P1] E falls
// to one lowest point s_j (value E_j, the "valley") and rises after it. A trajectory passes W in
// one time interval; let m be the instant of its lowest speed there: v_m ≤ v(s_j) ≤ E_j, and
// unless m is at an end of the interval, a(m) = 0 (a is continuous under a jerk limit). Then
//   v(t) ≤ E_j + Φ(|t − t_m|),  Φ(t) = ∫₀ᵗ min(Amax, Jmax·u) du
// on both sides of m (a changes at most Jmax per second from 0), and v ≤ E(s) everywhere.
// When m is at an end of the interval, Φ(t) = Amax·t still holds.
//
// Time in W for a given position s_m of m: stepping forward from s_m in time steps h, the
// position after each step is at most the bound's position plus min(∫w, h·max E) over the
// step (w = E_j + Φ, E's maximum over an interval of W is at one of its ends); after the last
// step, the rest takes at least ∫ds/E. The same backwards from s_m. s_m is unknown: the window
// is cut into cells [a, b] (geometric, finest around s_j) and for s_m in [a, b] the time is at
// least T_left(a) + T_right(b), each side's clock started at its edge (the time spent between a
// and b pays for the later start of the clock: shifting a side's clock by δ saves it at most δ).
// The cells at the window's ends use Φ = Amax·t. The window's time is at least
//   max(∫_W ds/E, min over cells (T_left(a) + T_right(b))),
// and the bound is the sum over the windows (each a lower bound of the trajectory's time there).
//
// Peaks: E's highest points are lowered first by peak_caps() (below); what remains sharp there
// is what the bound leaves out (the true jerk-limited optimum rounds them more).
// On one line from rest to rest that reaches the feed and Amax it equals the closed form
// V/A + A/J + L/V (the rounding at both stops is the whole difference to the acceleration
// bound, A/J).
#pragma once

#include <vector>

namespace cncore::bound {

// One piece of the acceleration bound's envelope E (see above): length in mm (degrees for a
// rotary-only move), cap, joint speeds u0 and u1 in mm/s, accelerations a (rising) and d
// (falling) in mm/s².
struct EnvelopePiece {
  double length_mm = 0;
  double cap_mm_s = 0;
  double u0_mm_s = 0, u1_mm_s = 0;
  double accel_mm_s2 = 0, decel_mm_s2 = 0;
};

// Speed caps at the peaks of E (the ends of the windows) for jerk-limited motion. At a peak p
// with acceleration a ≥ 0, the acceleration u later is still ≥ −Jmax·u (and ≥ −Amax), so the
// speed is ≥ v_p − Φ0(u), Φ0 = Φ with α = 0, and the tool has reached at least p + D(u),
// D(u) = ∫₀ᵘ (v_p − Φ0). Every point x it has passed by u it passed at a speed ≥ v_p − Φ0(u)
// and ≤ E(x): so v_p ≤ E(x) + Φ0(u) at x = p + D(u) (x taken no farther than the next
// valley, where E stops falling). With a ≤ 0 the same holds backwards in time. v_p is at most
// the larger of the two highest speeds that pass (bisection; the cap is the lowest speed found
// to fail). The caps hold for every jerk-limited trajectory; the acceleration envelope run again
// with them is lower around the peaks. (It also levels the envelope sooner after a valley,
// which shortens the valley's lag: BoundBuilder takes the larger of the bounds with and without
// the caps.)
struct PeakCap {
  double s_mm = 0;  // path position (the sum of the pieces' lengths before it)
  double cap_mm_s = 0;
};
std::vector<PeakCap> peak_caps(const std::vector<EnvelopePiece>& pieces, double amax_mm_s2,
                               double jerk_mm_s3);

// Lower bound of the motion time (s) of any trajectory under E with |a| ≤ amax_mm_s2 and
// |jerk| ≤ jerk_mm_s3 along the path; ≥ ∫ds/E.
double jerk_motion_time_s(const std::vector<EnvelopePiece>& pieces, double amax_mm_s2,
                          double jerk_mm_s3);

// ∫ds/E over the whole envelope (the acceleration bound's motion time).
double envelope_time_s(const std::vector<EnvelopePiece>& pieces);

}  // namespace cncore::bound
