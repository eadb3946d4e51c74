// Acceleration-limited acc/dec before interpolation (issue 9).
//
// Units: path positions s in mm, the step u (the distance moved in one cycle, i.e. the speed in
// mm/cycle), accelerations in mm/cycle². A0 = Amax·τ² is the path acceleration limit.
//
// 1. Caps. Every speed limit of the look-ahead window is a *cap* (V, [c, e)): every cycle whose
//    step starts in [c, e), and every step that lands at or after c, is ≤ V.
//      - segment speed cap: V = Vb (shape, per-axis speed), [c, e) = the segment [s0, end);
//      - feed cap: V = F (times the runtime override OR), [s0, end);
//      - joint cap at a corner at path position j: V = Vg, [j − Vg, j + Vg). Not just the step
//        that crosses j: the step before it and the step after it are ≤ Vg too, so the cycle
//        that turns the corner is not also a cycle of speed change (the checker measures the
//        direction change from two consecutive chords: with chords Vg and Vg + A0 the measured
//        normal acceleration is √(1 + A0/Vg) times the corner's, up to √3 at a reversal).
//    Consecutive segments with the same cap share one cap (its e is moved on), so a fine CAM
//    path pays no per-segment work beyond one tree update per block.
//    Stops (the end of the window, the end of the program, dwell and waiting M-codes) come in
//    every cycle as CycleInput::stop_mm.
//
// 2. Variable acceleration, σ. A segment may allow less than A0: a line whose axis share d_i
//    times A0 exceeds axis i's limit a_i (A_seg = min(A0, a_i/d_i)), and an arc where the normal
//    acceleration v²/ρ and the tangential one share an axis (|a_axis| ≤ √(a_t² + a_n²) times the
//    axis share of the arc plane; with the resultant option bounded by Amax). On an arc we allow
//    a_n ≤ min(v_top²/ρ, 0.95·g) (v_top the highest speed the arc can be run at, g the tightest
//    axis limit over its share), so Vb = √(ρ·a_n), and a_t = min(A0, √(g² − a_n²)).
//    With r = A_seg/A0 ∈ (0, 1] per segment, define the acceleration-weighted path coordinate
//        σ(s) = ∫ r ds        (σ advances r·L over a segment of length L).
//    Braking at A_seg along s is braking at A0 along σ: d(v²)/dσ = 2·A_seg/r = 2·A0. So a speed
//    v at σ_s can still be brought down to V at σ_c iff   v² + 2·A0·σ_s ≤ V² + 2·A0·σ_c = K.
//    K is fixed when the cap arrives: it depends neither on s nor on the current state.
//
// 3. Backward pass in closed form. The braking constraint of every cap ahead is
//        v² + 2·A0·σ(s) ≤ K_i,   K_i = V_i² + 2·A0·σ(c_i),
//    so all caps ahead act through min_i K_i — a minimum over a sliding window (caps enter at
//    the back as blocks arrive and retire as the tool passes them). Here: tournament trees over
//    the caps' ids (planner::MinTree, O(log n) per cap, O(1) to read); no backward pass over
//    the window and no walk per cycle. The lowest r over a step's span (4.) is a range minimum
//    over the buffer slots (two more trees), so a step over many tiny segments costs O(log n).
//    Discrete form: a step x from s lands at q = s + x with σ(q) ≤ σ(s) + x (r ≤ 1), so
//        x² + 2·A0·(σ(s) + x) ≤ K   ⇔   x ≤ B(K, s) = √(A0² + K − 2·A0·σ(s)) − A0.
//    (i) A step that lands at or after c has σ(q) ≥ σ(c), hence x² ≤ V²: it meets V.
//    (ii) Following the bound is always possible: let x_k = B(K, s_k) exactly, R_k = K − 2A0σ_k
//        = x_k² + 2A0·x_k. The step moves σ by r·x_k, so R_{k+1} = x_k² + 2A0·x_k·(1 − r) and
//        x_{k+1} = √(A0² + R_{k+1}) − A0 ≥ x_k − r·A0 (square both sides: A0²(1−r)² ≤ A0²).
//        A step below the bound leaves more room, so the next bound is ≥ (this step) − r·A0:
//        the deceleration it asks for never exceeds the segment's A_seg = r·A0. The minimum of
//        several such bounds has the same property.
//    (iii) A cap is *active* (its plain V applies) for steps starting in [e_c, e), e_c its
//        entry; before e_c it acts through its K. At the point with σ(c) − σ(p) = V the bound
//        is exactly V (√(A0² + V² + 2·A0·V) − A0 = V, and in the lattice form below
//        √((V − A0/2)² + 2·A0·V) − A0/2 = V), so e_c is that point (entry_mm(); ≤ c − V as
//        r ≤ 1): switching to V there never needs a deceleration step, and from there every
//        step ≤ V meets the cap. (At c the bound is √(A0² + V²) − A0, 0.09·V for V = 0.3·A0:
//        with e_c = c the tool crawled towards a small cap in a zone of low r, 2.6 → 0.4
//        µm/cycle over 10 cycles before a 68° corner of cap 1.8 on line-contouring-xz.) On an
//        arc where 10. applies e_c stays at c (c − V for a lattice key): 10.'s curve ends at the
//        first entry, and the later, lower one leaves it more (arc_time 4.102 → 4.092 s).
//    Stops use the exact lattice form instead (V = 0 would never be reached with (ii)):
//        (x + A0/2)² ≤ A0²/4 + 2·A0·(σ(stop) − σ(s)).
//    Following it the steps are x, x − A0, …, A0 with the last step landing exactly on the
//    stop (the sum of A0 + 2A0 + … + n·A0 = n(n+1)A0/2 is exactly the right side's distance);
//    with r < 1 the decrement is ≤ r·A0 ((1/2 − r)² ≤ 1/4). The step that reaches the stop is
//    clipped to land on it (≤ A0: P4's arrival at ≤ Amax·τ), so the last sample is the stop.
//    Near the stop the landing step in real distance (x, x − a, …, landing exactly) and the
//    tail cap of 6. take a = A0 × the lowest r (with the joint zones, 7.) from the tool up to
//    the stop: that minimum only rises as the tool moves on and both bounds rise with a, so
//    following them never asks for more than a at once (with the r over the next step's reach
//    only, a short low-r segment before the stop came into reach at once: 3 698 mm/s² on a
//    2 000 axis; with the segments' r without the zones, the pair across a corner just before
//    the stop slowed by more than its zone leaves beside the turn: Y 2 018.7 on a 2 000 axis
//    0.05 mm before an exact stop, X 1 475.6 on a 1 400 axis 0.03 mm before the program's
//    end). A block arriving while the tool brakes for the window's end, whose r or joint zone
//    would lower these bounds at once below the last step, is held (6., check_stop()).
//
//    Caps of V ≥ A0 (and corner caps ≥ A0/2 on long segments with r ≥ 1/2) use the lattice
//    key instead, K = (V − A0/2)² + 2·A0·σ(c), x ≤ √(K − 2·A0·σ(s)) − A0/2: following it the steps
//    are exactly x, x − A0, …, and a step landing at or after c has (x − A0/2)² ≤ (V − A0/2)², so
//    x ≤ V. Its bound is V at c − V and may reach 0 just before c when V < A0 (the last lattice
//    step can be larger than V and then lands short of c), so such a cap is active from c − V
//    at the latest (e_c, (iii)).
//
// 4. Forward pass = the cycle:  u = min(u_prev + r·A0, caps active, B(min K), stop bound), r the
// lowest
//    over where the step can go (segments and joint zones, 7.). At a capped corner the zone's r
//    is what a speed change may use next to the turn at Vg (7.), so the speed may rise there
//    too: a rule that held it while any corner cap was active pinned it at V_t = A0/2 on
//    paths whose corner caps overlap (circles of 0.03 mm chords: 1 mm/s for 95 s).
//    Where the pair at the tool lies on one line (the last step started on it and this one,
//    even with the line's own r·A0 more, cannot leave it; no filter), the sample at the tool is
//    a plain speed change along the line: the rise is the line's own r·A0, not the lower r of
//    a joint zone ahead in the reach (7.'s pairs have their sample within V of the joint).
//    line-contouring-xz 22.193 → 22.048 s, cam-short-segments 7.215 → 7.154, braid_cut2d
//    20.076 → 19.884.
//
// 5. Feed caps and the override. A feed cap's V is OR·F and OR may change at any cycle, so its
//    key K = (OR·F)² + 2A0σ(c) depends on OR. We keep one key tree per override *level*
//    OR_j = j·Δ (Δ = 0.1 up to 400 %): a feed cap enters every level tree with the key for OR_j;
//    the cycle reads the tree of the highest level ≤ OR. K grows with OR, so that key is never
//    looser than the exact one: the braking target is OR_j·F ≤ OR·F (exact at 100 %, and at
//    every multiple of 10 %). Work: a feed cap costs one update of all levels when it arrives
//    and when it is activated (only where the feed changes: equal feeds share a cap, and
//    extending a cap to the next segment moves its position, not its tree leaves); the level
//    trees are stored node-major (planner::MinTreeRows: one path of 41-wide nodes per update)
//    over a pool of feed-cap ids, not over every cap slot; the cycle reads one root. An override
//    increase only raises the limits (the geometric caps and the stops, which keep every braking
//    distance, are OR-independent); an override decrease lowers the feed limit, and the tool then
//    decelerates at A_seg until it is below it (u ≥ u_prev − r·A0 for the feed part), which the
//    spec and the checker allow for one ramp. Without a filter at least at σ's mean r over the
//    step just taken, r̄: the keys of the level before allowed that step, so they allow it less
//    r̄·A0 now (3. (ii)), and r (the next reach's, 4.) may be below r̄ in a joint zone, whose
//    decreases σ runs at their own r (7.): decelerating at r·A0 there fell behind them. On an arc
//    whose r was set by the normal acceleration at its top speed, it decelerates at min(A0,
//    √((0.98·g)² − (u²/ρ)²)) for the current step u instead (more as u falls; inside the tool's
//    segment, no joint zone within reach, and not with a filter after this type, whose r carry (8.)
//    assumes r).
//
// 6. Late caps. A block arrives *late* when the interpreter was late: until then the window's
//    last end point was a stop, and the tool may already be braking for it. Its caps may then
//    bind at once: one whose c the commanded position has passed is active at once, and with a
//    filter (8.) the steps still in it were not bounded by it; one ahead may have a braking bound
//    below the last step (the stop's bounds are lattice and real-distance forms, a cap's key is
//    in σ with offset A0: they differ by up to A0/2, and by (1 − r)·A0 on a segment with r < 1).
//    Found (accel_late_test.cpp, before the hold): a corner, a slower feed or an arc arriving
//    during the braking ramp gave tangential accelerations up to 3 365 mm/s² (A 2 000), corners
//    passed at 5× their Vg with a 200-cycle jerk stage (normal 10 769 mm/s²), 0.022 mm of
//    rounding for a 0.01 mm tolerance, and without a filter on slow X/Y a late 30° corner braked
//    an r = 0.8 line at A0 (X 1 740 > 1 500 mm/s²).
//    So a block's range caps and its joint's cap are tested before anything is attached
//    (check_late(), from on_segment() or, at a joint, from joint_zones() before its zone is
//    applied, with σ(c) as low as the zone may leave it; late_cap(): active at once with V below
//    the largest commanded step of the last lag cycles, or approaching with its bound at the
//    commanded position below the last step — from at or above it, following it needs ≤ r·A0
//    per cycle, 3. (ii)), and so is the stop at the joint when the joint's zone (7.) lowers σ
//    ahead of the tool (its lattice bound must still allow the last step; found: a zone ahead of
//    a 1 µm segment gave 2 011.7 mm/s²), and the stop's landing bounds in real distance (3.)
//    at the block's end, with its r and its joint zone's (check_stop()); insert() tests what
//    these did not foresee (on_joint()'s cap for two corners in one cycle). Only when the tool
//    is near enough for anything to bind: every cap starts at or after s0 − (2 + reach_lag)·v_hi
//    (8.), and from c − p ≥ (u²/(2·A0) + u + A0)/r_lo on no key bound is below the step u (r_lo the
//    window's, the block's, and kZoneFloor × the lower r at its joint, the lowest its zone
//    may have). If one binds, the block is *held*: the window's end it
//    arrived at (hold_mm_) stays a stop, the caps of every block arriving meanwhile wait in
//    pending_ (and no joint zone reaches behind hold_mm_), and once the tool has been at rest
//    there for the post filter's length they are inserted with the σ(c) of then. The tool
//    starts from rest with an empty filter, so every cap holds from there on as in 1.–8.
//    A held block costs the rest of the stop and the filter's span (corner arriving during the
//    braking: +7 cycles without a filter, +21 with Tp = 16, +32 with T2 = 40, +191 with T2 = 200
//    and Tp = 16 against the old, violating runs; at most 10 cycles more than the same block in
//    time). Blocks in time, and late ones whose caps it can still follow, are attached as before
//    (same samples: bench_motion --digest). What makes the usual late block followable: the
//    last V_t = min(A0, a_i)/2 before every stop (V_t is the lowest corner cap, a reversal's) is
//    run at ≤ V_t, and the lattice's steps landing within V_t of the stop are ≤ V_t.
//    A step that followed 10.'s curve on an arc (above the keys' bounds) relied on its end e and
//    target W, which a late block may change: a cap entering before e (a lattice cap's entry
//    c − V, a joint cap's j − Vg) or a joint zone starting before it moves e back, and a cap
//    whose bound at σ(e) is below W lowers W. Either holds the block too (found: a 1 µm line
//    after a dwell, its lattice cap entering 0.11 mm before e while the tool braked on a helix:
//    the curve fell by 1.41·A0 at once, 2 827 mm/s² tangential).
//    The release inserts the pending caps kReleasePerCycle per cycle (O(log n) each) while the
//    tool waits at rest, so no cycle does more than a bounded number of inserts.
//
// 7. Joint zones: a turn and a speed change in the same cycles. Samples P[k] = p(s_k) on a path
//    with one corner at j (unit tangents E before, S after), steps u1 = s_k − s_{k−1} and
//    u2 = s_{k+1} − s_k with j in [s_{k−1}, s_{k+1}]: with α the part of step 1 after j and β the
//    part of step 2 before j,  P[k+1] − 2P[k] + P[k−1] = (u2 − u1)·S + c·(S − E), c = u1 − α − β,
//    c ∈ [min(0, u1 − u2), u1]. Linear in c: the extremes are c = u1 (a sample on the joint:
//    u2·S − u1·E) and c = min(0, u1 − u2) ((u2 − u1)·S or (u2 − u1)·E: a plain speed change,
//    within the segments' r). |u2·S_i − u1·E_i| is convex in (u1, u2), so over u1, u2 ≤ V,
//    |u2 − u1| ≤ D its maximum is at a vertex: (V, V), (V, V − D), (V − D, V), (D, 0), (0, D):
//        |V·(S_i − E_i)| ≤ a_i (the corner limit), D·|S_i|, D·|E_i| ≤ a_i (the segments' r), and
//        |V·(S_i − E_i) − D·S_i| ≤ a_i,   |V·(S_i − E_i) + D·E_i| ≤ a_i.
//    The corner limit alone uses the whole budget for the turn, the segments' r alone the whole
//    budget for the speed change: on a diagonal path with axis limits = Amax the last two add
//    both on one axis (measured up to 1.38 × the limit at gentle corners). At a reversal
//    (S = −E) or a right angle along the axes they need nothing more. So every joint without a
//    stop gets a *zone* in which r is lowered to r_j = D/A0, D the largest value meeting the
//    last two with V = V0, the corner's passing speed (or the larger of the segments' caps
//    where the corner allows more: the step after the joint starts in b and is bounded by b's
//    cap only — with the smaller one, an arc at 1 µm/cycle into a rapid turned 75° while the
//    step grew to 3 µm, 2 479 mm/s² on a 2 000 axis); a smaller V keeps them (convex in V, and
//    true at V = 0). When D would fall
//    below kZoneFloor·min(r_a, r_b)·A0, D = that floor and the corner is passed slower instead
//    (the largest V meeting both, a joint cap).
//    The zone covers [j − 2V, j + V] (V: the largest step near the joint, V_j or the segments'
//    caps): the speed change u2 − u1 of a pair around j is
//      - for an increase, ≤ A0 × the lowest r over where step 2 can go (step()), and step 2
//        starts in [j − V, j + V];
//      - for a decrease by a braking bound, ≤ A0 × the mean r over step 1 (3. (ii), in the
//        lattice forms the same: (1/2 − ρ)² ≤ 1/4), and step 1 lies in [j − 2V, j + V].
//    The zone is part of σ, so every braking plan already accounts for it; a feed limit is
//    followed exactly (no extra deceleration step) unless the override was just lowered.
//    Decreases and increases need different vertices: a decrease (u2 < u1, c ∈ [0, u1]) has the
//    extremes u2·S − u1·E and (u2 − u1)·S, so only |V·(S_i − E_i) − D·S_i| ≤ a_i and D·|S_i|,
//    D·|E_i| ≤ a_i; an increase (c ∈ [u1 − u2, u1]) only |V·(S_i − E_i) + D·E_i| ≤ a_i and the
//    same two. Decreases come from the braking bounds and an override decrease (σ's mean r over
//    step 1, 3. (ii), 5.), the stop's landing bounds and a hold (the lowest r over the reach or
//    up to the stop, 3., 4.); increases from the reach's r. So without a filter σ takes the
//    zone's r for decreases alone, r_d = D_dec/A0 ≥ r_j (head_rd_, tail_rd_; at the V the zone
//    is sized for, V0 or the one lowered to the floor), and r_span() keeps r_j, the lower of
//    both. On a gentle corner whose turn leans on the speed increase's axis (the decrease
//    relieves it) r_d is far above the floor: line-contouring-xz's 4.8° corners brake at 0.82
//    instead of 0.25 × A0 next to the turn (22.348 → 22.193 s), cam-short-segments 7.279 →
//    7.215, braid_cut2d 20.338 → 20.076.
//    A zone lowers r on the tail of a (and of up to kZoneWalk earlier short segments) when b
//    arrives: σ after the first changed segment moves, so the starts of the later segments,
//    the window's end and the keys of the caps from there on are recomputed with the exact
//    σ(c) (a bounded number of caps per joint). Never under or behind the tool (a late joint).
//    Keys use the exact σ(c) (a σ below the true one lets the bound reach 0 before c, a stall).
//    Not covered: a zone reaching back over more than kZoneWalk segments (tiny segments with a
//    sharp corner: the corner cap then keeps V small, so 2V spans few of them).
//    Chains: when a (and the segment before it) is shorter than a step, one pair of steps can
//    turn from E (the end of the segment before the chain) to S at once, the middle tangent M
//    over length L between. The extremes are then u2·S − u1·E + L·(E − M) (the sample on the
//    last joint, step 1 over the whole chain) and u2·S − u1·E + L·(M − S) (on the first, step 2
//    over it); with M_i = λE_i + (1 − λ)S_i, λ ∈ [0, 1], both are (u2 − u1)·S_i + c·(S_i − E_i)
//    with c = u1 − (1 − λ)L or u1 − λL, inside the range of c above: the vertex bounds hold with
//    E and S, each axis less L·(how far M_i lies outside [E_i, S_i]). So the zone of the chain's
//    last joint also meets them for the turn E → S at the chain's V (the lower of both joints'
//    caps), and reaches back over the middle (the pairs' steps lie in [c − 2V, j + V], c the
//    first corner); below the floor the chain is passed at the V that fits the floor — a cap on
//    both joints — or, if that is below L, at L (no step then skips the middle, and each
//    corner's own zone holds). Sized for the turn alone (the speed change left to the zones of
//    the single corners), a 1.3 µm line between two corners gave 1 407 mm/s² on a 1 400 axis.
//    Longer chains (a polyline fillet, a tiny polygon: many corners within one step) are bounded
//    by the kernel (planner/turn_window.hpp): the joint's speed V keeps V·spread_i ≤ a_i, the
//    spread of the tangent over (j − V, j]; given that spread T, the zone here also meets
//    |Δu|·max|e_i| + V·T_i ≤ a_i and |Δu| + V·|T| ≤ A0 (d_max), and where its reach back over
//    kZoneWalk segments falls short of 2V the chain is passed at what that reach covers.
//
// 8. Jerk stage and post filter. With a jerk limit the tool's step is the moving average of the
//    last T2 commanded steps (T2 = ⌈2·Amax/(Jmax·τ)⌉, planner::make_limits): its acceleration is
//    (u_k − u_{k−T2})/T2, within what the commanded steps use, and its jerk
//    (a_k − a_{k−T2})/T2 ≤ 2·A0/T2 ≤ Jmax·τ³ — tangential jerk; the tool stays on the path, the
//    filter runs on the path position. The post-interpolation filter (Tp cycles, kernel) averages
//    the axis positions after it; its corner rounding v·(Tp + 1)·sin θ/8 ≤ tolerance holds when
//    the speed is ≤ the corner's Vg (planner::joint_speed_pc) for the Tp cycles around the corner.
//    Both average the commanded motion over at most lag = T2 + Tp cycles (the steps a late
//    block must respect, 6.). How far that reaches along the path: the jerk stage's output
//    position is the mean of the last T2 commanded positions x_0 < … < x_{T2−1}, its step the
//    mean of the commanded steps that start there. Let every commanded step that starts in
//    [c − W, e + W) or lands at or after c − W be ≤ V, W = (T2 − 1)/2·V. An output step that
//    starts in [c, e) (mean ≥ c) has x_0 ≥ c − W: else the positions from the first one at or
//    after c − W on rise by ≤ V a cycle from below c − W + V, and the mean stays below
//    c − W + (T2 − 1)/2·V = c. Likewise x_{T2−1} < e + W. So it averages only steps ≤ V. Its
//    acceleration averages the step changes over one commanded step more: (T2 + 1)/2·V. The
//    post filter averages axis positions off the path; it keeps its whole Tp·V. So, with
//    cap_lag = (T2 − 1)/2 + Tp and reach_lag = (T2 + 1)/2 + Tp (both T2 + Tp until session 16:
//    zigzag_0.002 at T2 = 4 ran 34.54 s, now 26.54):
//      - every cap reaches cap_lag·V further on both sides, a corner
//        [j − (1 + cap_lag)·Vg, j + (1 + cap_lag)·Vg);
//      - a joint zone (7.) spans [j − (2 + reach_lag)·V, j + (1 + reach_lag)·V] (past b into the
//        segments after it through a carried head zone);
//      - the output at p averages the commanded accelerations up to reach_lag·v ahead of p, so
//        a segment with r < 1 carries its r over the next reach_lag·v_top mm (a head zone of the
//        later segments; v_top the highest step allowed so far).
//    A block arriving late (6.), whose widened caps would start behind the commanded position
//    over steps already in the filter, is held until the tool has stopped at its start and the
//    filter has emptied: no cap then starts behind a step the filter still averages
//    (accel_late_test.cpp: corners of 30–179°, slower feeds and arcs arriving at every point of
//    the braking ramp, random programs with random arrival cycles; T2 = 4–200, Tp = 8–16).
//
// 9. The cycle after a capped corner. A joint cap holds the step after the crossing at Vg too,
//    because the crossing's sample may lie anywhere around j. Once the crossing is done, where
//    it lies is known: with α the part of the crossing step before j and β the part after, the
//    chords are d1 = α·E + β·S and d2 = u2·S, so the second difference at the sample after j is
//    (u2 − β)·S − α·E — only α of the turn is left to it (none when the crossing sample lies on
//    j). Between two lines (linear axes, no filter) after_corner() computes the interval of u2
//    that keeps every axis, the tangential and the normal acceleration (and the resultant
//    option) there, and replaces the joint's cap and its head zone by it for that one step: the
//    samples after it see plain speed changes along S (b's own r). Kept only when the interval
//    holds u1 − ρ·A0 (every step a cycle may choose lies in [u1 − ρ·A0, its bounds]; ρ as in
//    11.: the larger of σ's mean r over the crossing step and the r of b's piece at the tool,
//    what a hold or an override decrease slows by — in this cycle they keep that r, only the
//    increase gets b's own) and the step stays inside b. The steps before the corner and the
//    crossing step are unchanged, so every braking plan still holds. Capped corners along a
//    lattice approach put the crossing sample near j, and the speed then rises by up to A0 at
//    once: zigzag_0.002 22.53 → 20.54 s. (With u1 − A0 as the lower end, a corner inside its
//    zone at the floor, r = 0.25, never had an interval: line-contouring-xz's 4.8° corners.)
//
// 10. Braking on an arc with what the speed leaves. On an arc whose r was fixed for its top speed
//    (2.), the braking bounds (3.) decelerate at r·A0 = √(g² − a_n,top²) at every speed, where
//    a(v) = min(A_c, √(g'² − (v²/ρ)²)) is allowed (A_c = min(A0, the linear axes' share);
//    arc_time braked at 0.31·A0 all the way down from 139 mm/s). While the tool is on
//    such an arc (no filter, the step before also on it), let e be the end of the arc before its
//    tail zone (7.), or the first entry of a cap not yet active if that is earlier, and W the
//    lowest braking bound of the keys at σ(e) (3.; the geometric and lattice keys, and the feed
//    keys of the override level separately). Every cap not yet active starts at or after e, so
//    reaching e at ≤ W and following the keys from there meets all of them. Back from e, with
//    q = v², dq/dp = −2·a(√q) gives the largest q at p from which a(v) still reaches W at e:
//        Q(p) = W² + 2·A_c·(e − p) up to q* = ρ·√(g'² − A_c²) (where a stops being A_c), then
//        Q = ρg'·sin(θ), θ = θ* + 2·(e − p − d*)/ρ (d/dp of ρg'·sin θ is −2g'·cos θ = −2·a),
//        ρg' once θ ≥ π/2; Q = W² past e.
//    The bound T is the step x with x² = Q(s + x) (Newton from above on the convex
//    x² − Q(s + x), accepted only below the root). A step x_k ≤ T lands at s_{k+1} with
//    x_k² ≤ Q(s_{k+1}), and the next bound has x_{k+1}² = Q(s_{k+1} + x_{k+1}), so
//    x_k² − x_{k+1}² ≤ Q(s_{k+1}) − Q(s_{k+1} + x_{k+1}) ≤ 2·x_{k+1}·a(x_{k+1}) (a grows as q
//    falls, and Q ≥ x_{k+1}² over that stretch): x_k − x_{k+1} ≤ a(x_{k+1}), the same argument as
//    3. (ii) with a(v) for r·A0; a step landing past e is ≤ W, which the keys allow. Each braking
//    bound b then becomes max(b, T): both are bounds from which the next cycle's bound is at most
//    one allowed deceleration lower, so their maximum is too.
//    a is taken at the later (smaller) step while the pair's normal acceleration is up to
//    u1²/ρ: with d ≤ a(u2), a(u2)² + (u1²/ρ)² − (u2²/ρ)² ≤ g'² + 4·d·u1³/ρ² ≤ g'² + 2g'²φ +
//    12g²φ² (φ = u1/ρ ≤ V_b/ρ, d·u1²/ρ ≤ g'²/2 + 3g²φ), so g'² = g²·min(0.98², 1 − 2.5φ −
//    12φ²) keeps the pair within g (the 2 % of 5. for the chords at small φ).
//    The stop's bounds are not relaxed; in real distance they take the lowest r up to the stop
//    (3.), so a state above the keys' bounds meets no lower r coming into the step's reach there
//    (with the reach's r: a short arc before the window's end, 0.63 → 0.19 µm/cycle² at once).
//
// 11. Centred corners (between two lines, linear axes, no filter, turns ≤ 120°, b ≥ Vg + A0).
//    The joint cap holds the step that lands within Vg before j to Vg as well, because the
//    crossing after it may split the turn anyhow (9.). With the step u0 landing α before j and
//    the crossing u1 = α + β, the sample between them has the second difference
//    (α − u0)·E + β·S: the turn is shared between this sample and the next (9.) as β : α. So u0
//    may exceed Vg where that sample keeps every limit for every u1 the next cycle may take:
//      - u1 ≤ Vg: the sample lands in [c, j) = [j − Vg, j), where the cap is active;
//      - u1 ≥ u0 − ρ·A0: every bound but this cap's allowed u0 (the step is ≤ the cycle's
//        bound with this cap's key or active leaf left out, the stop's bounds included), so
//        each allows u0 − r̄·A0 next, r̄ = Δσ/u0 the mean r over the step (3. (ii); the stop's
//        landing bounds take the lowest r up to the stop, ≤ r̄); a hold or an override decrease
//        slows by A0 × the r of the next step's reach, ≤ the r of the piece the step lands in
//        (an override decrease by at most r̄·A0 more, 5.); ρ the larger (slowdown_r()). (With r_hi,
//        the highest r from the tool to j, a step from before a tail zone at the floor counted on
//        slowing by A0 at the sample, and the committing step was never feasible there.)
//    The limits at the sample: per axis |(α − u0)·E_i + β·S_i| ≤ a_i, tangential |u1 − u0| ≤ A0
//    (path speeds), the checker's chord normal a_n² = 2·u0·(|d1| − α − β·c) ≤ A0² (c = E·S,
//    increasing in β), resultant |d1 − d0|² ≤ A0². Each is convex in u1 on u1 ≤ α (no crossing:
//    a plain speed change) and on u1 ≥ α, so the ends of both pieces decide (centred_ok()). The
//    sample after the crossing is 9.'s (or, where 9. gives no interval, the cap's Vg as before:
//    7.'s pair of steps ≤ Vg, whatever b's length: the crossing is ≤ Vg as without 11.; b ≥
//    Vg + A0 keeps it inside b, so d1 = α·E + β·S). The sample stays ≥ 10 nm before j (the
//    checker takes a sample that close as reaching the joint). The step u0 is the largest
//    feasible one up to that bound: the per-axis limits with u1 = Vg are linear in u0
//    (α = j − tool − u0), their largest u0 first, then a bisection of 6 checks (every answer is
//    checked itself).
//    One step earlier (the tool ≥ 2·Vg + A0 before j): a step u_{-1} above the cap's bound
//    (≤ the cycle's bound without it) is taken when from its landing point p0 the slowest next
//    step, u_{-1} − ρ·A0 (ρ of that step), is a feasible centred step (lands in [c, j), limits
//    as above). It is *committed*: the cycle at p0 takes the largest feasible centred step
//    ≥ that (or the held step under a hold, if feasible), and every bound but the cap's allows
//    it there by 3. (ii).
//    The braking lattice of the cap's key lands the tool at c − Vg with Vg + A0; from there the
//    two steps let it reach the bound's pattern …, V + A0, **V** (centred), V + A0 …
//    (zigzag_0.002: 20.54 → 18.54 s; with ρ for r_hi and b ≥ Vg + A0, line-contouring-xz
//    22.575 → 22.348 s, braid_cut2d 20.526 → 20.338 s). Cost: only within 3·Vg + 3·A0 of such a
//    corner, a few closed forms and two tree updates (the cap's leaf left out and put back).
//
// 12. Rises across one joint (pair_rise()). The zones (7.) hold a pair of steps anywhere in
//    [j − 2V, j + V] to r_j, sized for the corner's V and any sample position. For an increase
//    the cycle knows both: the step just taken u1 and where the joint lies. When the pair spans
//    exactly one joint between two lines (no filter, no hold, no stop in reach, no resultant
//    option), its second difference has the extremes D·E and u1·(S − E) + D·S (7., c linear),
//    so D is the largest value with |u1·(S_i − E_i) + D·S_i| ≤ a_i on every axis and
//    D ≤ min(r_a, r_b)·A0. Decreases keep the zones (σ): the braking plans do not change.
//    circle_small_segments 12.926 → 12.768 s; the sampled reference (bench/bound, cncore-sref)
//    runs it in 10.924 s: what is left there is the joint caps' hold of the steps beside the
//    crossing and the zones' r for decreases, sized for the caps rather than the speeds run.
//
// 13. Zones sized again for the next cap (rezone_before()). A zone is sized when its joint
//    arrives, for the speed V the tool may have there: the corner's cap, or what it can reach
//    from the cap before it. The cap vc of the next joint, when it arrives, bounds the speed over
//    the zone too (its braking bound, 3.). Where that V' is well below V and the tool has not
//    reached the zone, the zone is sized again for V' (shorter, with more room for the speed
//    change: r only rises, σ and the keys after it are recomputed) and the joint's cap lowered
//    to V', so that the zone's premise holds by the cap whatever comes later. Only plain zones
//    (two lines, no turn-window chain, no filter). line-contouring-xz 22.023 → 21.955 s: a 2°
//    joint 0.25 mm before a 68° corner had its zone sized for 46 µm/cycle. A zone whose tail
//    reached back over up to kRezoneWalk segments keeps their tails as they were before it
//    (LastZone::walk), restored and zoned again for V'; a chain's zone (a shorter than the step,
//    7.) only where V' ≤ a's length, where no step skips a and each corner's own zone holds
//    (line-contouring-xz 21.932 → 21.922 s).
//    That bound carries the lattice's and 11.'s slack (+A0, +2·A0), large where A0 is large
//    against the speeds. Where braking at A0 over b leaves less, V_r = √(vc² + 2·A0·L_b) − A0/2,
//    and a zone sized for it has ≥ 20 % more room for the speed change, the zone is sized for
//    V_r and the joint capped there instead, if the tool can still follow that cap (a choice:
//    a lower cap may cost a cycle's rounding; line-contouring-xz 21.922 → 21.864 s,
//    circle_small_segments 12.517 → 12.435). Forward, a joint's zone is sized the same way for
//    what the caps before it leave, √(vc² + 2·A0·d) (joint_zones(): circle_small 12.276 s,
//    line-contouring-xz 21.848).
//
// Without a filter the tool position is the commanded position and at rest means step 0.
#include "motion/accel_limited.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace cncore::motion {

using planner::ItemKind;
using planner::MinTree;
using planner::Segment;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
// The filters after this type (8.): the jerk stage's T2 and the post filter's Tp, 0 when off.
double jerk_cycles(const planner::Limits& l) {
  return l.t2_cycles > 1 ? l.t2_cycles : 0.0;
}
double post_cycles(const planner::Limits& l) {
  return l.post_filter() ? l.post_cycles : 0.0;
}
constexpr double kArcNormalShare = 0.95;  // a_n ≤ 0.95·g on arcs where the axes couple
constexpr double kRecoverShare = 0.98;  // √(a_t² + a_n²) ≤ 0.98·g slowing down on an arc (5.)
// Joint zones (7.): the speed change allowed at a joint is at least this share of the segments'
// (below it, the corner's passing speed is lowered instead).
constexpr double kZoneFloor = 0.25;
constexpr std::size_t kReleasePerCycle = 32;  // pending caps a cycle inserts (6.)
constexpr std::size_t kZoneWalk = 16;         // segments a joint zone may reach back over
constexpr double kRezoneGain = 1.2;   // 13.: a zone sized below its braking bound gains this much D
constexpr double kMinAlphaMm = 1e-5;  // 11.: the sample before a centred crossing, before j
constexpr int kCentreSearch = 6;      // 11.: bisection steps of a centred step search

// The largest step x from which the tool can still stop exactly at distance d with steps that
// shrink by at most a per cycle: x + (x − a) + (x − 2a) + … (positive terms, the last one ≤ a
// landing on the stop) ≤ d. With m the largest integer with a·m(m+1)/2 ≤ d this is
// x = d/(m+1) + a·m/2 (d ≤ a: x = d, the landing step). Following it the steps are exactly
// x, x − a, x − 2a, …: f(x) = x + f(x − a), so after the step the rest is f(x − a).
double landing_step(double d, double a) {
  if (d <= a) return d;
  double m = std::floor((std::sqrt(8 * d / a + 1) - 1) / 2);
  while (m > 0 && a * m * (m + 1) / 2 > d) m -= 1;
  while (a * (m + 1) * (m + 2) / 2 <= d) m += 1;
  return d / (m + 1) + a * m / 2;
}

// A bound b = √X − c is left out of a minimum when X ≥ above(t + c) = (t + c)²·(1 + kSkipMargin):
// then √X − c ≥ t + (t + c)·kSkipMargin/2 exactly, far above the few roundings of either side.
constexpr double kSkipMargin = 1e-9;
// The cosine c = E·S of the turn between two lines that move X, Y, Z only; false when a rotary
// axis moves (the closed forms of 9. and 11. are for linear axes).
bool linear_turn_cos(const AxisVec& e, const AxisVec& s, double& c) {
  for (std::size_t i = 3; i < kMaxAxes; ++i) {
    if (e[i] != 0 || s[i] != 0) return false;
  }
  c = dot(e.xyz(), s.xyz());
  return true;
}

// The largest x in (u, hi] with ok(x) (11.'s step searches): hi itself, else the best of a
// bisection of kCentreSearch checks (every answer is checked itself); u when none is found.
template <typename Ok>
double largest_ok(double u, double hi, Ok ok) {
  if (ok(hi)) return hi;
  double lo = u, best = u;
  for (int it = 0; it < kCentreSearch; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (ok(mid)) {
      best = mid;
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return best;
}

double above(double x) {
  return x * x * (1 + kSkipMargin);
}

// Segments shorter than a step between corners (a chain, 7.): tangent at both ends, length,
// sweep (0 on a line).
struct ChainMid {
  AxisVec start_dir, end_dir;
  double len_mm = 0, sweep_rad = 0;
};

// A chain's share of axis i beyond the turn from e to s: with the middle tangent M over length
// L, the extremes of the second difference over the whole chain (7.: a sample on its first or
// last joint, one step over all of it) are u2·S − u1·E + L·(E − M) and u2·S − u1·E + L·(M − S).
// M_i = λE_i + (1 − λ)S_i with λ ∈ [0, 1] makes them (u2 − u1)·S_i + c·(S_i − E_i) with
// c = u1 − (1 − λ)·L or u1 − λ·L, inside 7.'s range of c: the turn from E to S alone. M_i
// outside [E_i, S_i] by ε adds ≤ L·ε (an arc's tangent moves by ≤ its sweep).
double chain_slack(const AxisVec& e, const AxisVec& s, const ChainMid* mid, std::size_t n,
                   std::size_t i) {
  const double lo = std::min(e[i], s[i]), hi = std::max(e[i], s[i]);
  double slack = 0;
  for (std::size_t m = 0; m < n; ++m) {
    const double out = std::max({0.0, mid[m].start_dir[i] - hi, lo - mid[m].start_dir[i],
                                 mid[m].end_dir[i] - hi, lo - mid[m].end_dir[i]});
    slack += mid[m].len_mm * (out + mid[m].sweep_rad);
  }
  return slack;
}

// The largest speed change d ≤ d0 per cycle that a chain from e to s passed at v leaves room
// for (7.'s vertices with E, S and the slack; < 0: the turn alone is too much).
double chain_d_max(const AxisVec& e, const AxisVec& s, const ChainMid* mid, std::size_t n, double v,
                   double d0, const planner::Limits& lim) {
  double d = d0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim.axis_on[i] || lim.axis_amax_pc2[i] <= 0) continue;
    const double ai = lim.axis_amax_pc2[i] - chain_slack(e, s, mid, n, i);
    const double t = v * (s[i] - e[i]);
    if (std::abs(t) > ai) return -1;
    if (std::abs(s[i]) > 1e-12)
      d = std::min(d, std::min(ai, ai + (s[i] > 0 ? t : -t)) / std::abs(s[i]));
    if (std::abs(e[i]) > 1e-12)
      d = std::min(d, std::min(ai, ai - (e[i] > 0 ? t : -t)) / std::abs(e[i]));
  }
  return d;
}

// The largest V at which a chain from e to s leaves room for a speed change d (linear in V:
// |V·Δ_i − d·S_i|, |V·Δ_i + d·E_i| ≤ a_i − slack, Δ = S − E); 0 where even V = 0 does not.
double chain_speed_pc(const AxisVec& e, const AxisVec& s, const ChainMid* mid, std::size_t n,
                      double d, const planner::Limits& lim) {
  double v = kInf;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim.axis_on[i] || lim.axis_amax_pc2[i] <= 0) continue;
    const double ai = lim.axis_amax_pc2[i] - chain_slack(e, s, mid, n, i);
    // (d ≤ a_i/|S_i| is what the segments' r gives, up to rounding: a relative margin.)
    if (d * std::max(std::abs(s[i]), std::abs(e[i])) > ai * (1 + 1e-9)) return 0;
    const double delta = s[i] - e[i];
    if (std::abs(delta) <= 1e-12) continue;
    const double sg = delta > 0 ? 1.0 : -1.0;
    v = std::min({v, ai / std::abs(delta), (ai + d * s[i] * sg) / std::abs(delta),
                  (ai - d * e[i] * sg) / std::abs(delta)});
  }
  return std::max(v, 0.0);
}

bool straight_joint(const AxisVec& u, const AxisVec& w) {
  double q = 0;
  for (std::size_t i = 0; i < kMaxAxes; ++i) q += (u[i] - w[i]) * (u[i] - w[i]);
  return q <= 1e-18;
}
}  // namespace

AccelLimitedAccDec::AccelLimitedAccDec(const planner::SegmentBuffer& buffer,
                                       const planner::Limits& limits, double or_max,
                                       bool check_reference_walk)
    : buf_(buffer),
      lim_(limits),
      a0_(limits.amax_pc2),
      or_max_(std::max(1.0, or_max)),
      level_step_(or_max_ <= 4.0 ? 0.1 : or_max_ / 40.0),
      // 41 levels: 0 … 400 % by 10 %, or 40 equal steps up to a higher ORmax.
      levels_(std::min(kMaxLevels,
                       static_cast<std::size_t>(std::floor(or_max_ / level_step_ + 1e-9)) + 1)),
      sigma0_(buffer.capacity(), 0.0),
      ratio_(buffer.capacity(), 1.0),
      vcap_(buffer.capacity(), 0.0),
      len_mm_(buffer.capacity(), 0.0),
      head_mm_(buffer.capacity(), 0.0),
      head_r_(buffer.capacity(), 1.0),
      tail_mm_(buffer.capacity(), 0.0),
      tail_r_(buffer.capacity(), 1.0),
      head_rd_(buffer.capacity(), 1.0),
      tail_rd_(buffer.capacity(), 1.0),
      s0_mm_(buffer.capacity(), 0.0),
      pieces_(buffer.capacity(), SigmaPieces{}),
      arc_g_(buffer.capacity(), 0.0),
      arc_rho_(buffer.capacity(), 0.0),
      lin_r_(buffer.capacity(), 1.0),
      pool_(buffer.capacity() + kOverflow),
      caps_(3 * pool_, Cap{}),
      state_(3 * pool_, State::kEmpty),
      owner_(3 * (buffer.capacity() + kOverflow), kNone),
      where_(3 * pool_, kNone),
      free_(3 * pool_),
      entry_(3 * pool_),
      key_geo_(3 * pool_),
      key_lattice_(3 * pool_),
      active_geo_(3 * pool_),
      active_feed_(3 * pool_),
      release_(3 * pool_),
      key_feed_(pool_, levels_),
      feed_v_(pool_, 0.0),
      feed_k_(pool_, kInf),
      overflow_(3 * buffer.capacity()),
      r_zone_(buffer.capacity()),
      check_(check_reference_walk),
      jerk_(limits.t2_cycles > 1 ? limits.t2_cycles : 1),
      jerk_on_(limits.t2_cycles > 1),
      lag_(jerk_cycles(limits) + post_cycles(limits)),
      reach_lag_((jerk_on_ ? 0.5 * (jerk_cycles(limits) + 1) : 0.0) + post_cycles(limits)),
      cap_lag_(reach_lag_ - (jerk_on_ ? 1.0 : 0.0)) {
  // Free ids, lowest on top.
  for (std::size_t k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < pool_; ++i) {
      free_[k * pool_ + i] = static_cast<std::uint32_t>(k * pool_ + pool_ - 1 - i);
    }
    free_n_[k] = pool_;
  }
  tail_cap_pc_ = a0_;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (lim_.axis_on[i] && lim_.axis_amax_pc2[i] > 0) {
      tail_cap_pc_ = std::min(tail_cap_pc_, lim_.axis_amax_pc2[i]);
    }
  }
  tail_cap_pc_ *= 0.5;
  recent_.assign(std::max<std::size_t>(1, static_cast<std::size_t>(lag_)), 0.0);
  // At most three caps per buffer slot wait for a hold's release: no allocation when they come.
  pending_.reserve(3 * buffer.capacity());
}

double AccelLimitedAccDec::segment_accel_pc2(std::uint64_t index) const {
  return a0_ * ratio_[buf_.slot(index)];
}

void AccelLimitedAccDec::on_segment(std::uint64_t index, const Segment& s) {
  const std::size_t slot = buf_.slot(index);
  const AxisVec delta = s.end - s.start;
  double r = 1;
  double vcap = s.vb_pc;
  // Per-axis acceleration along the direction: d_i·A ≤ a_i (lines; on arcs the linear axes
  // outside the plane and the rotary axes move linearly too).
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    // On a helix the axis along the arc's normal rises linearly: its share is rise/L.
    const double d = s.arc && i < 3 ? std::abs(s.rise_mm * component(s.n, i)) / s.length_mm
                                    : std::abs(delta[i]) / s.length_mm;
    if (d > 1e-12) r = std::min(r, lim_.axis_amax_pc2[i] / (d * a0_));
  }
  lin_r_[slot] = std::max(r, 1e-6);
  arc_g_[slot] = 0;
  if (s.arc) {
    // Normal and tangential acceleration share the axes of the arc plane: an axis sees at most
    // √(a_t² + a_n²)·h_i (h_i its share of the plane).
    double g = kInf;
    for (std::size_t i = 0; i < 3; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      const double h = std::hypot(component(s.e1, i), component(s.e2, i));
      if (h > 1e-9) g = std::min(g, lim_.axis_amax_pc2[i] / h);
    }
    if (lim_.bound_resultant) g = std::min(g, a0_);
    if (g < std::sqrt(2.0) * a0_) {
      const double v_top = std::min(s.vb_pc, s.feed_pc * or_max_);
      const double an = std::min(v_top * v_top / s.rho_mm, kArcNormalShare * g);
      vcap = std::min(vcap, std::sqrt(an * s.rho_mm));
      r = std::min(r, std::min(a0_, std::sqrt(std::max(0.0, g * g - an * an))) / a0_);
      arc_g_[slot] = g;
      arc_rho_[slot] = s.rho_mm;
    }
  }
  r = std::max(r, 1e-6);
  ratio_[slot] = r;
  vcap_[slot] = vcap;
  len_mm_[slot] = s.length_mm;
  s0_mm_[slot] = s.s0_mm;
  head_mm_[slot] = tail_mm_[slot] = 0;
  head_r_[slot] = tail_r_[slot] = 1;
  head_rd_[slot] = tail_rd_[slot] = 1;
  refresh_pieces(slot);
  // Head zones reaching here from earlier segments (8.); expired ones are dropped.
  for (std::size_t k = 0; k < n_carries_;) {
    if (carries_[k].until_mm <= s.s0_mm) {
      carries_[k] = carries_[--n_carries_];
      continue;
    }
    add_head(slot, carries_[k].until_mm - s.s0_mm, carries_[k].r, carries_[k].r);
    ++k;
  }
  if (lag_ > 0) {
    vtop_pc_ = std::max(vtop_pc_, std::min(vcap, s.feed_pc * or_max_));
    // The output at p averages the commanded accelerations up to reach_lag·v ahead of it (8.):
    // a commanded step may use only the lowest r of the reach_lag·v behind it.
    if (r < 1) carry(s.end_mm() + reach_lag_ * vtop_pc_, r);
  }

  const bool contiguous = have_prev_ && prev_end_mm_ == s.s0_mm;
  // A joint (the kernel calls on_joint next) unless an event that stops lies between.
  bool joint = contiguous && prev_index_ >= buf_.begin_index() &&
               buf_[prev_index_].kind == ItemKind::kMotion;
  for (std::uint64_t k = prev_index_ + 1; joint && k < index; ++k) joint = !buf_[k].barrier;
  // A block arriving late (6.): a cap it brings that would slow the commanded position below
  // its step at once (or, active at once, below the steps still in the filter) holds it.
  late_check_ = false;
  if (!late_hold_) {
    // Every cap it brings starts at or after s0 − (2 + reach_lag)·v_hi: joint caps
    // (1 + cap_lag)·Vg before the joint, a lattice cap's entry V before that, and Vg ≤ the
    // faster side's cap (8.). From c − p ≥ d/r_lo on, σ(c) − σ_p ≥ d = u²/(2·A0) + u + A0, and
    // both key forms (3.) give a bound ≥ u there.
    const double v_hi =
        std::max({vcap, s.feed_pc * or_max_, have_prev_ ? vcap_[buf_.slot(prev_index_)] : 0.0});
    // (With this block's own r and the lowest its joint's zone may have, kZoneFloor of the
    // lower r at the joint (7.): the stop's landing bounds use them, far from d/r_lo on they
    // are ≥ u as well, 3.)
    const double r_prev = have_prev_ ? ratio_[buf_.slot(prev_index_)] : 1.0;
    const double r_lo =
        std::max(1e-6, std::min({1.0, r_zone_.min(), r, kZoneFloor * std::min(r, r_prev)}));
    const double near_mm =
        (2 + reach_lag_) * v_hi + (step_ * step_ / (2 * a0_) + step_ + a0_) / r_lo;
    if (pos_mm_ + near_mm >= s.s0_mm) {
      late_m_ = step_;
      for (const double x : recent_) late_m_ = std::max(late_m_, x);
      late_check_ = late_m_ > 0;
      late_at_mm_ = s.s0_mm;
    }
  }
  n_late_range_ = 0;
  if (late_check_) {
    late_sigma_p_ = sigma_at(pos_mm_);
    const double v[2] = {vcap, s.feed_pc};
    const double reach_k[2] = {cap_lag_ * vcap, cap_lag_ * s.feed_pc * or_max_};
    for (std::size_t k = 0; k < 2; ++k) {
      // The same limit as the previous segment extends its cap: nothing new (see below).
      const std::size_t from = 3 * buf_.slot(prev_index_) + k;
      if (contiguous && owner_[from] != kNone && caps_[owner_[from]].v == v[k]) continue;
      const double c = s.s0_mm - reach_k[k];
      late_range_[n_late_range_++] = {c,      s.end_mm() + reach_k[k], v[k], 0,
                                      k == 1, k == 0 && vcap >= a0_};
    }
    // With this block's end as the window's new stop, an r of its own lowers the stop's
    // bounds (found: a 0.1 mm helix at r = 0.29 arriving while the tool braked on a line,
    // T2 = 4: the commanded step fell by 2.02·A0 in one cycle, 2 126 mm/s² after the jerk
    // stage); its joint's zone is tested in joint_zones().
    if (r < 1) check_stop(s.end_mm(), s.s0_mm, r);
    // At a joint, joint_zones() tests them with the σ its zone will leave.
    if (!joint && !late_hold_) check_late(s.s0_mm, 0, 1, nullptr);
  }
  if (joint) joint_zones(prev_index_, slot, s);
  update_r(index);
  sigma0_[slot] = sigma_total_;
  sigma_total_ += seg_sigma(slot, s.length_mm);
  // With a filter after this type (8.) a cap reaches cap_lag·V further on both sides (a feed
  // cap's speed is up to OR_max·F).
  const double reach[2] = {cap_lag_ * vcap, cap_lag_ * s.feed_pc * or_max_};
  auto widened = [&](double v, bool feed, bool lattice, double r_reach) {
    Cap cap{s.s0_mm - r_reach, s.end_mm() + r_reach, v, sigma0_[slot], feed, lattice};
    if (r_reach > 0) cap.sigma_c = sigma_at(cap.c_mm);
    return cap;
  };
  const Cap caps[2] = {widened(vcap, false, vcap >= a0_, reach[0]),
                       widened(s.feed_pc, true, false, reach[1])};
  for (std::size_t k = 0; k < 2; ++k) {
    const std::size_t to = 3 * slot + k;
    if (contiguous) {
      const std::size_t from = 3 * buf_.slot(prev_index_) + k;
      if (owner_[from] != kNone && caps_[owner_[from]].v == caps[k].v) {
        // Same limit as the previous segment: extend its cap (moved to this slot so that the
        // buffer can retire the earlier segments; its keys and entry do not change).
        clear(to);
        move(from, to);
        const std::size_t g = owner_[to];
        caps_[g].e_mm = s.end_mm() + reach[k];
        // An active cap keeps its earlier release position in release_ (≤ e): step() moves it
        // on when the tool gets there, once per window's length instead of one tree update per
        // block (an extended cap is the tree's minimum, so each update walked to the root).
        if (state_[g] != State::kActive && pos_mm_ >= caps_[g].entry) activate(g);
        continue;
      }
    }
    insert(to, caps[k]);
  }
  have_prev_ = true;
  prev_index_ = index;
  prev_end_mm_ = s.end_mm();
}

void AccelLimitedAccDec::insert_joint_cap(std::size_t slot_a, std::size_t slot_b, double joint_mm,
                                          double len_a, double vg) {
  // σ(j − Vg), exact (inside a directly, before a by a search of the buffer): a key with a σ
  // lower than the true σ(c) would make the bound reach 0 before c (a stall) where r < 1.
  // The cap covers the step before and after the joint, and cap_lag·Vg more with a filter (8.).
  const double w = vg * (1 + cap_lag_);
  const double c_mm = joint_mm - w;
  const double sigma_c =
      w <= len_a ? sigma0_[slot_a] + seg_sigma(slot_a, len_a - w) : sigma_at(c_mm);
  // Lattice form where it cannot stall before the cap takes over (see 3.): V ≥ A0, or V ≥ A0/2
  // with mean r ≥ 1/2 over [c − V, c] (the bound is 0 at (V − V²/A0)/(2·r) ≤ V/2 before c).
  bool lattice = vg >= a0_;
  if (!lattice && vg >= 0.5 * a0_) lattice = sigma_c - sigma_at(c_mm - vg) >= 0.5 * vg;
  // Kept in b's slot: the range reaches into b (and past it when b is short), and b stays in
  // the buffer anyway while the tool is in it; in a's slot, a full small buffer could wait for
  // a block that cannot arrive before a is retired.
  insert(3 * slot_b + 2, Cap{c_mm, joint_mm + w, vg, sigma_c, false, lattice});
}

void AccelLimitedAccDec::on_joint(std::uint64_t index_a, const Segment& a, const Segment& b) {
  const std::size_t sa = buf_.slot(index_a);
  const std::size_t sb = buf_.slot(buf_.end_index() - 1);
  // Without a joint cap the steps next to the joint are bounded by the faster side's cap (the
  // step after the joint starts in b): the corner is passed at up to the larger of both.
  const double around = std::max(vcap_[sa], vcap_[sb]);
  // The corner alone (no slow-corner stop rule: that belongs to the moving average).
  // (joint_zones() computed the corner's speed for this same joint when b arrived.)
  const double corner =
      zone_index_a_ == index_a ? zone_joint_pc_ : planner::joint_speed_pc(a, b, lim_, false);
  double vg = std::min(corner, around);
  // Lowered where the turn leaves too little of the axis budget for the speed change (7.).
  if (zone_index_a_ == index_a) vg = std::min(vg, zone_vg_);
  // The directions at the joint, as joint_zones() computed them for it (the same doubles).
  const bool zoned = zone_index_a_ == index_a;
  const AxisVec a_end = zoned ? zone_e_ : a.end_direction();
  const AxisVec b_start = zoned ? zone_s_ : b.start_direction();
  const bool chained = prev_.valid && prev_.index_b == index_a;
  // A segment shorter than one step lets one cycle turn two corners at once (from the end of
  // the segment before a to the start of b; after another short one, three). Either the speed
  // stays ≤ a's length (no step skips a) or the combined turn is allowed (as in the moving
  // average type). Only where the combined turn allows less than the caps already in force.
  if (chained && a.length_mm < vg) {
    const double pair = planner::turn_speed_pc(prev_.end_dir, b_start, lim_);
    double both = pair < 0.999 * std::min(prev_.vg, vg) ? pair : kInf;
    // The chain's turn beside the speed change its zone allows (joint_zones(), 7.).
    if (zone_index_a_ == index_a && zone_chain_vg_ < 0.999 * prev_.vg) {
      both = std::min(both, zone_chain_vg_);
    }
    if (prev_.short_a) {
      const double triple = planner::turn_speed_pc(prev_.end_dir2, b_start, lim_);
      if (triple < 0.999 * std::min({prev_.vg2, prev_.vg, vg})) both = std::min(both, triple);
    }
    if (both < kInf) {
      const double cap = std::max(a.length_mm, both);
      vg = std::min(vg, cap);
      if (cap < prev_.vg) {
        // The joint before a (at a's start) gets the same cap.
        const std::size_t sx = buf_.slot(prev_.index_a);
        if (buf_.begin_index() <= prev_.index_a) {
          insert_joint_cap(sx, sa, a.s0_mm, buf_[prev_.index_a].length_mm, cap);
        }
        prev_.vg = cap;
      }
    }
  }
  const AxisVec before = chained ? prev_.end_dir : a_end;
  const double vg_before = chained ? prev_.vg : kInf;
  prev_ = {true,
           index_a,
           buf_.end_index() - 1,
           a_end,
           before,
           vg,
           vg_before,
           a.length_mm < vg,
           zoned ? zone_a_start_ : a.start_direction(),
           a.length_mm,
           a.arc && a.rho_mm > 0 ? a.length_mm / a.rho_mm : 0.0};
  // A turn in the same cycle as a speed change: the joint zones (7.) keep both within every
  // axis limit (at a capped corner the cap is lowered until the zone's floor fits beside it).
  if (!(vg < 0.999 * around)) return;  // the segments' own caps already hold there
  insert_joint_cap(sa, sb, a.end_mm(), a.length_mm, vg);
}

void AccelLimitedAccDec::on_retire(std::uint64_t index) {
  const std::size_t slot = buf_.slot(index);
  const std::size_t s = 3 * slot;
  clear(s);
  clear(s + 1);
  clear(s + 2);
  // The slot may next hold an event (no on_segment): no r there. Every leaf ≥ 1 means "no
  // limit" to r_span() (rates are ≤ 1), so a leaf of 1 is left as it is: the usual retirement
  // writes nothing to the tree.
  if (r_zone_.at(slot) < 1) r_zone_.set(slot, MinTree::kEmpty);
}

bool AccelLimitedAccDec::detach(std::uint64_t index) {
  // The caps of a segment the tool has passed are active ones (their range started behind the
  // tool) whose range reaches past it: a joint cap [j − Vg, j + Vg) over segments shorter than
  // Vg, or any cap widened by cap_lag·V with a filter (8.). They move to the overflow positions
  // of their kind (3·(capacity + i) + k, so that pos % 3 still tells a joint cap), kept as a set
  // where none dominates another (lower V and later end); a cap dominated by one there is
  // dropped, and with all kOverflow taken it merges with the one of the nearest V as
  // (min V, max e): stricter than each, so every cap still holds. (A single merged position
  // ran a 103 mm helix at the 1 mm/s of a 1 µm F60 line before it: a rapid's feed cap, widened
  // by 200 cycles × 2 × 0.25 mm to 100 mm, took line's V; T2 = 200, lookahead 8, G61.)
  const std::size_t s = 3 * buf_.slot(index);
  for (std::size_t k = 0; k < 3; ++k) {
    if (pos_state(s + k) == State::kApproaching) return false;
  }
  for (std::size_t k = 0; k < 3; ++k) {
    if (pos_state(s + k) != State::kActive) continue;
    const Cap cap = caps_[owner_[s + k]];
    constexpr std::size_t kNoPos = ~std::size_t{0};
    std::size_t free_pos = kNoPos;
    std::size_t nearest = kNoPos;
    double nearest_ratio = -1;
    bool dominated = false;
    for (std::size_t i = 0; i < kOverflow; ++i) {
      const std::size_t o = overflow_ + 3 * i + k;
      if (pos_state(o) != State::kActive) {
        free_pos = o;
        continue;
      }
      const Cap& x = caps_[owner_[o]];
      if (x.v <= cap.v && x.e_mm >= cap.e_mm) {
        dominated = true;
        break;
      }
      if (cap.v <= x.v && cap.e_mm >= x.e_mm) {
        clear(o);
        free_pos = o;
        continue;
      }
      const double ratio = std::min(x.v, cap.v) / std::max(x.v, cap.v);
      if (ratio > nearest_ratio) {
        nearest_ratio = ratio;
        nearest = o;
      }
    }
    if (dominated) {
      clear(s + k);
    } else if (free_pos != kNoPos) {
      move(s + k, free_pos);  // active, its trees unchanged
    } else {
      clear(s + k);
      const std::size_t g = owner_[nearest];
      Cap& merged = caps_[g];
      merged.v = std::min(merged.v, cap.v);
      merged.e_mm = std::max(merged.e_mm, cap.e_mm);
      (merged.feed ? active_feed_ : active_geo_).set(g, merged.v);
      release_.set(g, merged.e_mm);
    }
  }
  return true;
}

void AccelLimitedAccDec::insert(std::size_t pos, const Cap& cap) {
  // (A cap the checks in on_segment() did not foresee, e.g. on_joint()'s lower cap for two
  // corners within one cycle, still holds the block when it binds at once.)
  if (!rekeying_ && !late_hold_ && late_check_ && late_cap(cap)) start_hold(late_at_mm_);
  if (late_hold_ && !rekeying_ && !releasing_) {
    pending_.emplace_back(pos, cap);  // takes effect when the hold ends (release_hold())
    return;
  }
  clear(pos);
  const std::size_t kind = pos % 3;
  const std::size_t g = free_[kind * pool_ + --free_n_[kind]];
  owner_[pos] = static_cast<std::uint32_t>(g);
  where_[g] = static_cast<std::uint32_t>(pos);
  caps_[g] = cap;
  const double entry = entry_mm(cap);
  caps_[g].entry = entry;
  if (pos_mm_ >= entry) {
    activate(g);
    return;
  }
  state_[g] = State::kApproaching;
  set_keys(g, entry);
}

void AccelLimitedAccDec::set_keys(std::size_t g, double entry) {
  const Cap& cap = caps_[g];
  entry_.set(g, entry);
  const double k_sigma = 2 * a0_ * cap.sigma_c;
  if (cap.lattice) {
    const double h = cap.v - 0.5 * a0_;
    key_lattice_.set(g, h * h + k_sigma);
  } else if (cap.feed) {
    feed_v_[g - pool_] = cap.v;
    feed_k_[g - pool_] = k_sigma;
    update_feed_group(g - pool_);
  } else {
    key_geo_.set(g, cap.v * cap.v + k_sigma);
  }
}

void AccelLimitedAccDec::move(std::size_t from, std::size_t to) {
  const std::uint32_t g = owner_[from];
  owner_[to] = g;
  owner_[from] = kNone;
  where_[g] = static_cast<std::uint32_t>(to);
}

double AccelLimitedAccDec::entry_mm(const Cap& cap) const {
  // A cap takes over where its key's bound has come down to V, σ(c) − σ(e) = V (3. (iii)).
  // A feed cap's V follows the override: it takes over at c. On an arc where 10. applies, and
  // where the search meets an event item, at c − V for a lattice key, else c (later, lower).
  const double late = cap.lattice ? cap.c_mm - cap.v : cap.c_mm;
  if (cap.feed) return late;
  std::size_t slot = 0;
  const double e = mm_at_sigma(cap.sigma_c - cap.v, cap.c_mm, slot);
  if (slot >= buf_.capacity() || arc_g_[slot] > 0) return late;
  return std::min(cap.c_mm - cap.v, e);
}

double AccelLimitedAccDec::mm_at_sigma(double target, double hint_mm, std::size_t& slot) const {
  // The lowest path position p (from the start of the tool's segment, or of the window's first)
  // with σ(p) ≥ target, for a target ≤ σ(hint_mm): back from hint_mm's item by galloping over
  // the items' σ at their starts, then bisection, then inside the segment's pieces. O(log n).
  // slot = capacity (none) where the items searched are not all motion items.
  slot = buf_.capacity();
  if (buf_.empty() || !have_prev_) return hint_mm;
  const std::uint64_t first = std::max(cur_, buf_.begin_index()), end = buf_.end_index();
  if (first >= end) return hint_mm;
  auto sigma0 = [&](std::uint64_t k) { return sigma0_[buf_.slot(k)]; };
  std::uint64_t hi = buf_.seek(first, hint_mm, UINT64_MAX, end - 1);
  if (!buf_.is_motion(hi)) return hint_mm;
  std::uint64_t lo = hi;
  if (sigma0(hi) > target) {
    // Invariant: σ0(hi) > target; then σ0(lo) ≤ target.
    for (std::uint64_t step = 1;; step *= 2) {
      const std::uint64_t probe = hi - std::min(step, hi - first);
      if (probe == hi || !buf_.is_motion(probe)) {
        // σ reaches the target before the first item searched: at its start (not the tool's
        // position: with the tool's item retired, the tool may still be before it).
        if (probe == hi) slot = buf_.slot(hi);
        return s0_mm_[buf_.slot(hi)];
      }
      if (sigma0(probe) <= target) {
        lo = probe;
        break;
      }
      hi = probe;
    }
    while (hi - lo > 1) {
      const std::uint64_t mid = lo + (hi - lo) / 2;
      if (!buf_.is_motion(mid)) return hint_mm;
      (sigma0(mid) <= target ? lo : hi) = mid;
    }
  }
  slot = buf_.slot(lo);
  const SigmaPieces& pc = pieces_[slot];
  const double t = target - sigma0_[slot];
  double x = 0;
  if (t > 0) {
    if (t <= pc.sig1 && pc.p1 > 0) {
      x = t / pc.rate0;
    } else if (t <= pc.sig2 && pc.p2 > pc.p1) {
      x = pc.p1 + (t - pc.sig1) / pc.rate1;
    } else {
      x = pc.p2 + (t - pc.sig2) / pc.rate2;
    }
    x = std::min(x, pc.len);
    // Rounding: σ(p) ≥ target exactly as seg_sigma() computes it.
    for (int it = 0; it < 4 && x < pc.len && seg_sigma(slot, x) < t; ++it) {
      x = std::nextafter(x, kInf);
    }
  }
  return s0_mm_[slot] + x;
}

void AccelLimitedAccDec::clear_keys(std::size_t g) {
  const Cap& cap = caps_[g];
  entry_.set(g, MinTree::kEmpty);
  if (cap.lattice) {
    key_lattice_.set(g, MinTree::kEmpty);
  } else if (cap.feed) {
    feed_k_[g - pool_] = kInf;
    update_feed_group(g - pool_);
  } else {
    key_geo_.set(g, MinTree::kEmpty);
  }
}

void AccelLimitedAccDec::update_feed_group(std::size_t i) {
  // The minima of the group of feed ids around i, level by level: the keys set_keys() gave
  // them, (j·step·V)² + 2·A0·σ(c), the same doubles (feed_key()).
  std::array<double, kMaxLevels> m;
  m.fill(kInf);
  const std::size_t lo = i / planner::MinTreeGroups::kFan * planner::MinTreeGroups::kFan;
  const std::size_t hi = std::min(pool_, lo + planner::MinTreeGroups::kFan);
  for (std::size_t k = lo; k < hi; ++k) {
    if (feed_k_[k] == kInf) continue;
    for (std::size_t j = 0; j < levels_; ++j) {
      const double key = feed_key(k, j);
      m[j] = key < m[j] ? key : m[j];
    }
  }
  key_feed_.set_group(i / planner::MinTreeGroups::kFan, m.data());
}

void AccelLimitedAccDec::activate(std::size_t g) {
  const Cap& cap = caps_[g];
  if (state_[g] == State::kApproaching) {
    clear_keys(g);
  }
  state_[g] = State::kActive;
  (cap.feed ? active_feed_ : active_geo_).set(g, cap.v);
  release_.set(g, cap.e_mm);
}

void AccelLimitedAccDec::clear(std::size_t pos) {
  const std::size_t g = owner_[pos];
  if (g == kNone) return;
  const bool feed = caps_[g].feed;
  if (state_[g] == State::kApproaching) {
    clear_keys(g);
  } else {
    (feed ? active_feed_ : active_geo_).set(g, MinTree::kEmpty);
    release_.set(g, MinTree::kEmpty);
  }
  state_[g] = State::kEmpty;
  owner_[pos] = kNone;
  where_[g] = kNone;
  const std::size_t kind = g / pool_;
  free_[kind * pool_ + free_n_[kind]++] = static_cast<std::uint32_t>(g);
}

void AccelLimitedAccDec::update_r(std::uint64_t index) {
  const Segment& s = buf_[index];
  const std::size_t slot = buf_.slot(index);
  if (s.kind != ItemKind::kMotion) {
    r_zone_.set(slot, MinTree::kEmpty);
    return;
  }
  // r_span()'s rate of a segment inside [from, to] as a whole (from ≤ s0, end ≤ to), written
  // as there so that the minimum is the same bit for bit.
  double rate = ratio_[slot];
  if (0.0 < head_mm_[slot]) rate = std::min(rate, head_r_[slot]);
  if (s.end_mm() - s.s0_mm > s.length_mm - tail_mm_[slot]) rate = std::min(rate, tail_r_[slot]);
  // (A slot usually holds 1 already: on_retire() leaves leaves of 1.)
  if (r_zone_.at(slot) != rate) r_zone_.set(slot, rate);
}

void AccelLimitedAccDec::add_head(std::size_t slot, double mm, double r, double r_dec) {
  if (mm <= 0 || r >= 1) return;
  head_r_[slot] = head_mm_[slot] > 0 ? std::min(head_r_[slot], r) : r;
  head_rd_[slot] = head_mm_[slot] > 0 ? std::min(head_rd_[slot], r_dec) : r_dec;
  head_mm_[slot] = std::max(head_mm_[slot], mm);
  refresh_pieces(slot);
}

void AccelLimitedAccDec::carry(double until_mm, double r) {
  if (n_carries_ == kCarries) {
    // Full: merge the two that end first (the lower r over the longer reach: stricter).
    std::sort(carries_.begin(), carries_.end(),
              [](const Carry& x, const Carry& y) { return x.until_mm < y.until_mm; });
    carries_[1] = {carries_[1].until_mm, std::min(carries_[0].r, carries_[1].r)};
    carries_[0] = carries_[--n_carries_];
  }
  carries_[n_carries_++] = {until_mm, r};
}

bool AccelLimitedAccDec::late_cap(const Cap& cap) const {
  const double or_ratio = cap.feed ? prev_or_ : 1.0;
  // Active at once: every step still in the filter must be within it.
  if (pos_mm_ >= entry_mm(cap)) return or_ratio * cap.v < late_m_;
  // Approaching: its braking bound at the commanded position (3.) must allow the last step,
  // from which following it needs no more than r·A0 per cycle (3. (ii)).
  const double k_sigma = 2 * a0_ * cap.sigma_c;
  const double h = cap.v - 0.5 * a0_;
  const double v = cap.feed ? static_cast<double>(level_of(or_ratio)) * level_step_ * cap.v : cap.v;
  auto bound_at = [&](double sigma) {
    return cap.lattice ? lattice(h * h + k_sigma, sigma) : brake(v * v + k_sigma, sigma);
  };
  if (bound_at(late_sigma_p_) < step_) return true;
  // The last step followed 10.'s curve to W at e: a cap entering before e moves e back, one
  // whose bound at e is below W lowers W; either may lower that curve by more than one cycle's
  // deceleration (found: a late line's lattice cap entering 0.11 mm before e, 2 827 mm/s²).
  if (relied_e_mm_ == kInf) return false;
  if (entry_mm(cap) < relied_e_mm_) return true;
  const double w = cap.feed ? relied_w_feed_ : relied_w_geo_;
  return w < kInf && bound_at(relied_sigma_e_) < w;
}

void AccelLimitedAccDec::check_late(double at_mm, double zone_mm, double zone_r,
                                    const Cap* joint_cap, std::uint64_t index_a) {
  // σ(c) as the joint zone [zone_mm, at_mm] of rate zone_r (1: none) will leave it, or lower.
  const double r_lo = std::min({1.0, r_zone_.min(), zone_r});
  const double sigma_zone = zone_r < 1 ? sigma_at(zone_mm) : 0;
  auto sigma_c = [&](double c) {
    const double sc = sigma_at(c);
    return zone_r < 1 && c > zone_mm ? std::min(sc, sigma_zone + r_lo * (c - zone_mm)) : sc;
  };
  // A zone starting before the e of 10.'s curve the last step followed moves e (the arc's tail)
  // or σ(e) (see late_cap()).
  if (zone_r < 1 && relied_e_mm_ < kInf && zone_mm < relied_e_mm_) start_hold(at_mm);
  for (std::size_t k = 0; k < n_late_range_ && !late_hold_; ++k) {
    Cap cap = late_range_[k];
    cap.sigma_c = sigma_c(cap.c_mm);
    if (late_cap(cap)) start_hold(at_mm);
  }
  if (joint_cap != nullptr && !late_hold_) {
    Cap cap = *joint_cap;
    cap.sigma_c = sigma_c(cap.c_mm);
    bool binds = late_cap(cap);
    if (!cap.lattice && cap.v >= 0.5 * a0_) {
      cap.lattice = true;  // insert_joint_cap() may choose either form here (3.): test both
      binds = binds || late_cap(cap);
    }
    if (binds) start_hold(at_mm);
  }
  // The caps of earlier blocks that the zone re-keys (joint_zones()) with the σ(c) it leaves:
  // one that binds at once holds the block before the zone is applied (found: a 1 µm G0's zone
  // with a 200-cycle jerk stage lowered σ under the tool over 0.66 mm; the re-keyed joint cap
  // bound, the hold began in the middle of the re-keying and left the older caps' keys stale:
  // a 0.54 µm/cycle cap met at 4.97 µm/cycle, 22 258 mm/s³ on a 20 000 jerk limit).
  if (zone_r >= 1 || late_hold_) return;
  std::size_t walked = 0;
  for (std::uint64_t k = index_a + 1;
       k-- > std::max(cur_, buf_.begin_index()) && walked < kZoneWalk && !late_hold_;) {
    const Segment& x = buf_[k];
    if (x.kind != ItemKind::kMotion) {
      if (x.barrier) break;
      continue;
    }
    if (x.end_mm() <= zone_mm) break;
    ++walked;
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t cs = 3 * buf_.slot(k) + c;
      if (pos_state(cs) != State::kApproaching) continue;
      Cap cap = caps_[owner_[cs]];
      cap.sigma_c = std::min(cap.sigma_c, sigma_c(cap.c_mm));
      if (late_cap(cap)) start_hold(at_mm);
    }
  }
}

void AccelLimitedAccDec::check_stop(double stop_mm, double at_mm, double r_new) {
  // The stop's landing step and tail cap (3.) use the lowest r (with the zones) from the tool
  // up to the stop: with stop_mm as the window's new stop and r_new as low as a new block
  // brings into that span, they must still allow the last step.
  if (step_ <= 0 || late_hold_) return;
  const double a_new = std::min(r_new, r_span(pos_mm_, at_mm)) * a0_;
  const double d = stop_mm - pos_mm_;
  const double vt = tail_cap_pc_;
  const double tail =
      d <= vt ? vt : std::sqrt(a_new * a_new + vt * vt + 2 * a_new * (d - vt)) - a_new;
  if (std::min(landing_step(d, a_new), tail) < step_) start_hold(at_mm);
}

void AccelLimitedAccDec::start_hold(double at_mm) {
  late_hold_ = true;
  hold_mm_ = at_mm;
  rest_cycles_ = 0;
}

void AccelLimitedAccDec::release_hold() {
  // kReleasePerCycle caps per cycle, so the cycle stays O(log n); the tool waits at rest at
  // hold_mm_ until the last one is in (blocks arriving meanwhile queue behind them).
  late_check_ = false;  // (the inserts below are not a block's arrival)
  releasing_ = true;
  const std::size_t end = std::min(pending_.size(), pending_next_ + kReleasePerCycle);
  for (; pending_next_ < end; ++pending_next_) {
    auto& [pos, cap] = pending_[pending_next_];
    // σ ahead may have moved since (joint zones of later blocks): keys with the exact σ(c), 7.
    cap.sigma_c = sigma_at(cap.c_mm);
    if (pos % 3 == 2 && cap.v < a0_) {
      cap.lattice = cap.v >= 0.5 * a0_ && cap.sigma_c - sigma_at(cap.c_mm - cap.v) >= 0.5 * cap.v;
    }
    insert(pos, cap);  // in arrival order: a later cap at the same position replaces it
  }
  releasing_ = false;
  if (pending_next_ == pending_.size()) {
    pending_.clear();
    pending_next_ = 0;
    late_hold_ = false;
  }
  cached_stop_mm_ = -1;
}

void AccelLimitedAccDec::advance_current() {
  if (buf_.empty()) return;
  cur_ = std::max(cur_, buf_.begin_index());
  // Skip the segments the tool has passed by a galloping search over the buffer's end
  // positions (many tiny segments per cycle); the walk below then only steps over events.
  auto passed = [&] {
    return cur_ + 1 < buf_.end_index() &&
           (buf_[cur_].kind != ItemKind::kMotion || pos_mm_ >= buf_[cur_].end_mm());
  };
  if (!passed()) return;  // the usual cycle: still inside the same segment
  // Hint: as many items as the last cycle that left its item skipped (fine segments of even
  // length at an even speed: a probe or two).
  const std::uint64_t from = cur_;
  cur_ = buf_.seek(cur_, pos_mm_, UINT64_MAX, cur_ + cur_skip_);
  while (passed()) ++cur_;
  cur_skip_ = cur_ - from;
}

double AccelLimitedAccDec::sigma_at(double pos_mm) const {
  if (!have_prev_ || pos_mm >= prev_end_mm_ || buf_.empty()) return sigma_total_;
  // The last item starting at or before pos_mm (items are in path order), then back to a
  // motion item: O(log n), only when the stop position changes.
  const std::uint64_t first = std::max(cur_, buf_.begin_index());
  std::uint64_t lo = first, hi = buf_.end_index();
  if (lo >= hi) return sigma_total_;
  // s0 of item k is the end of item k − 1, read from the buffer's compact array: a probe of 8
  // bytes instead of a cold ~330-byte Segment. Galloping back from the window's end first (the
  // caps of a new block, and their zones, ask for positions near it), then bisection:
  // invariant s0(hi) > pos (or hi the end), and lo = first or s0(lo) ≤ pos.
  for (std::uint64_t step = 1; hi - first > step; step *= 2) {
    const std::uint64_t probe = hi - step;
    if (buf_.end_mm_of(probe - 1) <= pos_mm) {
      lo = probe;
      break;
    }
    hi = probe;
  }
  while (hi - lo > 1) {
    const std::uint64_t mid = lo + (hi - lo) / 2;
    if (buf_.end_mm_of(mid - 1) <= pos_mm) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  std::uint64_t i = lo;
  while (i > buf_.begin_index() && buf_[i].kind != ItemKind::kMotion) --i;
  const Segment& s = buf_[i];
  if (s.kind != ItemKind::kMotion) return sigma_total_;
  const std::size_t slot = buf_.slot(i);
  return sigma0_[slot] + seg_sigma(slot, pos_mm - s.s0_mm);
}

void AccelLimitedAccDec::refresh_pieces(std::size_t slot) {
  // Pieces [0, h), [h, L − t), [L − t, L] (overlapping zones: the lower r of both). σ at the
  // piece ends is summed in the order seg_sigma() adds the pieces, so both give the same double
  // as summing the pieces up to x one by one (0 + y = y; an empty piece adds r·0 = 0).
  const double len = len_mm_[slot];
  const double r = ratio_[slot];
  const double h = std::min(head_mm_[slot], len);
  const double t0 = std::max(0.0, len - tail_mm_[slot]);
  const double pts[4] = {0, std::min(h, t0), std::max(h, t0), len};
  double rate[3];
  for (std::size_t k = 0; k < 3; ++k) {
    const double mid = 0.5 * (pts[k] + pts[k + 1]);
    rate[k] = r;
    if (mid < h) rate[k] = std::min(rate[k], head_rd_[slot]);
    if (mid > t0) rate[k] = std::min(rate[k], tail_rd_[slot]);
  }
  SigmaPieces& p = pieces_[slot];
  p.len = len;
  p.p1 = pts[1];
  p.p2 = pts[2];
  p.rate0 = rate[0];
  p.rate1 = rate[1];
  p.rate2 = rate[2];
  p.sig1 = pts[1] > 0 ? rate[0] * pts[1] : 0.0;
  p.sig2 = pts[2] > pts[1] ? p.sig1 + rate[1] * (pts[2] - pts[1]) : p.sig1;
}

double AccelLimitedAccDec::seg_sigma(std::size_t slot, double x_mm) const {
  const SigmaPieces& p = pieces_[slot];
  const double x = std::clamp(x_mm, 0.0, p.len);
  if (x <= p.p1) return x > 0 ? p.rate0 * x : 0.0;
  if (x <= p.p2) return p.sig1 + p.rate1 * (x - p.p1);
  return p.sig2 + p.rate2 * (x - p.p2);
}

double AccelLimitedAccDec::r_span(double from_mm, double to_mm, std::uint64_t* skip) const {
  double out = 1;
  if (buf_.empty()) return out;
  const std::uint64_t first = std::max(cur_, buf_.begin_index()), end = buf_.end_index();
  if (first >= end) return out;
  // One item of the walk "motion items from `first` while s0 ≤ to"; false: stop. From the
  // compact per-slot arrays (the same doubles as the Segment's): the pushes between two cycles
  // of fine segments evict the cold Segments the walk would otherwise load.
  auto item = [&](std::uint64_t k) {
    if (!buf_.is_motion(k)) return true;
    const std::size_t slot = buf_.slot(k);
    const double s0 = s0_mm_[slot];
    if (s0 > to_mm) return false;
    const double e = buf_.end_mm_of(k);
    if (e < from_mm) return true;
    double rate = ratio_[slot];
    if (std::max(from_mm, s0) - s0 < head_mm_[slot]) rate = std::min(rate, head_r_[slot]);
    if (std::min(to_mm, e) - s0 > len_mm_[slot] - tail_mm_[slot]) {
      rate = std::min(rate, tail_r_[slot]);
    }
    out = std::min(out, rate);
    return true;
  };
  // An item's rate over any part of it lies between its rate as a whole (its leaf of r_zone_,
  // kept current by update_r(); events and retired slots: ≥ 1) and 1. So where no leaf of the
  // items the walk may visit is below 1, the minimum is exactly 1 (the usual case between
  // joint zones): read from the compact leaves, not from the items.
  const std::size_t cap = buf_.capacity();
  auto range_min = [&](const MinTree& t, std::size_t a, std::size_t n) {
    return a + n <= cap ? t.min_range(a, a + n)
                        : std::min(t.min_range(a, cap), t.min_range(0, a + n - cap));
  };
  // The usual cycle: the step stays inside the tool's segment.
  const bool f_motion = buf_.is_motion(first);
  const double f_end = buf_.end_mm_of(first);
  if (f_motion && to_mm < f_end) {
    if (r_zone_.at(buf_.slot(first)) >= 1) return out;
    item(first);
    return out;
  }
  // The walk ends at or before `last`, the item containing to_mm (items after it start past
  // to_mm). Short spans: walked.
  // (Hint: the skip of the last call for the same kind of span, when the caller keeps one.)
  const std::uint64_t last =
      buf_.seek(first, to_mm, UINT64_MAX, skip != nullptr ? first + *skip : 0);
  if (skip != nullptr) *skip = last - first;
  // The leaves of first and last, and the minimum of those between (used again below).
  const double inner = last > first + 1 ? range_min(r_zone_, buf_.slot(first + 1),
                                                    static_cast<std::size_t>(last - first - 1))
                                        : MinTree::kEmpty;
  if (std::min(std::min(r_zone_.at(buf_.slot(first)), inner), r_zone_.at(buf_.slot(last))) >= 1) {
    return out;
  }
  if (last - first <= 8 || !f_motion || !(f_end > from_mm)) {
    for (std::uint64_t k = first; k <= last && item(k); ++k) {
    }
    return out;
  }
  // Long spans (many tiny segments per step): the first item (the tool's, ending after from_mm)
  // and the last one as in the walk; every item between starts after from_mm and ends at or
  // before to_mm (seek() skipped it), so its rate is that of the whole item: a range minimum.
  if (!item(first)) return out;
  out = std::min(out, inner);
  item(last);
  return out;
}

void AccelLimitedAccDec::resigma(std::uint64_t first, std::uint64_t index_a) {
  const Segment& a = buf_[index_a];
  const std::size_t sa = buf_.slot(index_a);
  // σ after the first changed segment moved: the starts of the later ones, the end of the
  // window, the cached σ of the stop, and the keys of the caps from there on (exact σ(c)).
  for (std::uint64_t k = first; k < index_a; ++k) {
    if (buf_[k].kind != ItemKind::kMotion) continue;
    const std::size_t sk = buf_.slot(k);
    double next = sigma0_[sk] + seg_sigma(sk, len_mm_[sk]);
    for (std::uint64_t n = k + 1; n <= index_a; ++n) {
      if (buf_[n].kind != ItemKind::kMotion) continue;
      sigma0_[buf_.slot(n)] = next;
      break;
    }
  }
  sigma_total_ = sigma0_[sa] + seg_sigma(sa, a.length_mm);
  cached_stop_mm_ = -1;
  const double from_mm = buf_[first].s0_mm;
  for (std::uint64_t k = first; k <= index_a; ++k) {
    if (buf_[k].kind != ItemKind::kMotion) continue;
    for (std::size_t c = 0; c < 3; ++c) {
      const std::size_t cs = 3 * buf_.slot(k) + c;
      if (pos_state(cs) != State::kApproaching || caps_[owner_[cs]].c_mm < from_mm) continue;
      const std::size_t g = owner_[cs];
      Cap cap = caps_[g];
      cap.sigma_c = sigma_at(cap.c_mm);
      if (c == 2 && cap.v < a0_) {
        cap.lattice = cap.v >= 0.5 * a0_ && cap.sigma_c - sigma_at(cap.c_mm - cap.v) >= 0.5 * cap.v;
      }
      // Unchanged and still ahead of the tool: nothing to do (insert() would set the same keys).
      if (cap.sigma_c == caps_[g].sigma_c && cap.lattice == caps_[g].lattice &&
          pos_mm_ < entry_mm(cap)) {
        continue;
      }
      rekeying_ = true;  // (a live cap's key follows the σ already changed above)
      insert(cs, cap);
      rekeying_ = false;
    }
  }
}

double AccelLimitedAccDec::plain_zone_d(const AxisVec& e, const AxisVec& s, double r_hi, double v,
                                        bool decreases_only) const {
  // 7.'s vertices between two lines (joint_zones()' d_max() without arcs or chains).
  double d = r_hi * a0_;
  for (std::size_t i = 0; i < kMaxAxes; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double ai = lim_.axis_amax_pc2[i];
    const double t = v * (s[i] - e[i]);
    if (std::abs(t) > ai) return -1.0;
    if (std::abs(s[i]) > 1e-12) {
      d = std::min(d, std::min(ai, ai + (s[i] > 0 ? t : -t)) / std::abs(s[i]));
    }
    if (std::abs(e[i]) > 1e-12) {
      d = std::min(d,
                   (decreases_only ? ai : std::min(ai, ai - (e[i] > 0 ? t : -t))) / std::abs(e[i]));
    }
  }
  return d;
}

bool AccelLimitedAccDec::rezone_before(const LastZone& z, std::uint64_t index_b, double vc) {
  // 13. The zone of the joint j_a at b's start was sized for the speed V the tool may have
  // there. The cap vc of the joint j_b at b's end, now known, bounds every step over
  // [j_a − 2V', j_a + V'] by its braking bound (3.: x ≤ √(A0² + vc² + 2·A0·(j_b − s)) − A0
  // at s, σ(j_b) − σ(s) ≤ j_b − s), plus 2·A0 for 11.'s steps above it. Where that V' is well
  // below V and the tool has not reached the zone yet, the zone is sized again for V' (shorter,
  // with more room for the speed change) and j_a's cap lowered to V' (the zone's premise then
  // holds by the cap, as in the forward case). Only a plain zone (two lines, no turn-window
  // chain, no filter, b's head set by this joint alone) or a chain's where V' ≤ a's length.
  if (!z.valid || z.index_a + 1 != index_b || late_hold_ || z.n_walk == 0) return false;
  const std::uint64_t ia = z.index_a;
  const std::uint64_t first = z.walk[z.n_walk - 1].index;
  if (first < buf_.begin_index() || first < cur_) return false;
  // (The old zone, [j − 2V − its chain's middle, j], ahead of the tool too: σ under the tool is
  // in use.)
  if (!(z.j_mm - 2 * z.v - z.chain_mm > pos_mm_ + 2 * (step_ + a0_))) return false;
  const Segment& a = buf_[ia];
  const Segment& b = buf_[index_b];
  if (a.kind != ItemKind::kMotion || b.kind != ItemKind::kMotion) return false;
  double v = z.v;
  for (int it = 0; it < 8; ++it) {
    const double reach =
        std::sqrt(vc * vc + a0_ * a0_ + 2 * a0_ * (b.end_mm() - (z.j_mm - 2 * v))) + 2 * a0_;
    if (reach >= v) break;
    v = reach;
  }
  // The speed the tool can reach at j_a braking at A0 for vc over b, √(vc² + 2·A0·L_b), is far
  // below that bound where A0 is large against the speeds (a 13.6° joint 10.4 µm before a 55°
  // corner of line-contouring-xz: 6.8 against 14.8 µm/cycle). Sized and capped a little below
  // it, V_r = that − A0/2, the zone's speed change is the larger one of the lower V; the cap
  // costs a cycle's rounding where the tool would have passed faster, so only where it raises
  // the zone's D by 20 % or more (a choice, not a bound: each V with its cap is sound; the
  // measured trade is in bench/README.md, "Session 15"). Only where the tool can follow the new
  // cap (its key's bound at the tool, with σ as now — the new zone only raises r — is at least
  // the last step, 3. (ii)), and no committed step of 11. or step on 10.'s curve relies on what
  // is ahead.
  double d = -1;  // plain_zone_d() at v, once computed
  if (const double v_r = std::max(vc, std::sqrt(vc * vc + 2 * a0_ * b.length_mm) - 0.5 * a0_);
      v_r < v && !commit_.valid && relied_e_mm_ == kInf) {
    const double d_r = plain_zone_d(z.e, z.s, z.r_hi, v_r, false);
    if (d_r >= kRezoneGain * std::max(z.floor, plain_zone_d(z.e, z.s, z.r_hi, v, false))) {
      // The cap's key (3., either form insert_joint_cap() may choose) at the tool.
      const double sc = sigma_at(z.j_mm - v_r), sp = sigma_at(pos_mm_);
      const double h = v_r - 0.5 * a0_;
      if (sc > sp && brake(v_r * v_r + 2 * a0_ * sc, sp) >= step_ &&
          lattice(h * h + 2 * a0_ * sc, sp) >= step_) {
        v = v_r;
        d = d_r;
      }
    }
  }
  if (!(v < 0.95 * z.v)) return false;
  // A chain's zone (7.): at V' within its middle, a (no step skips it), each corner's own zone
  // holds, and this one is plain.
  if (z.chain_mm > 0 && !(v <= a.length_mm)) return false;
  // Every pair that may span j_a is still to come, each under j_b's cap.
  if (!(z.j_mm - 2 * v > pos_mm_ + 2 * (step_ + a0_))) return false;
  if (d < 0) d = plain_zone_d(z.e, z.s, z.r_hi, v, false);
  if (!(d >= z.floor)) return false;
  const double rj = std::max(d / a0_, 1e-6);
  const double rjd = std::max(rj, std::max(d, plain_zone_d(z.e, z.s, z.r_hi, v, true)) / a0_);
  const std::size_t sa = buf_.slot(ia), sb = buf_.slot(index_b);
  // A joint without a cap gets one only between segments of a step or more (as in 7.).
  const std::uint32_t g = owner_[3 * sb + 2];
  if (g == kNone) {
    double turn = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) turn = std::max(turn, std::abs(z.s[i] - z.e[i]));
    if (!(z.v * turn >= 0.25 * a0_ && a.length_mm >= 2 * v && b.length_mm >= v)) return false;
  }
  const bool zoned = rj < z.r_top;
  // The tails as they were before the zone (each walked segment), then the new zone's
  // [j − 2V', j] over them (shorter: a part of the same segments).
  const double zone_start = z.j_mm - 2 * v;
  for (std::size_t w = 0; w < z.n_walk; ++w) {
    const WalkedTail& t = z.walk[w];
    const std::size_t sx = buf_.slot(t.index);
    tail_mm_[sx] = t.mm;
    tail_r_[sx] = t.r;
    tail_rd_[sx] = t.rd;
    const Segment& x = buf_[t.index];
    if (zoned && x.end_mm() > zone_start) {
      const double covered = x.end_mm() - std::max(zone_start, x.s0_mm);
      tail_r_[sx] = t.mm > 0 ? std::min(t.r, rj) : rj;
      tail_rd_[sx] = t.mm > 0 ? std::min(t.rd, rjd) : rjd;
      tail_mm_[sx] = std::max(t.mm, covered);
    }
    refresh_pieces(sx);
    update_r(t.index);
  }
  head_mm_[sb] = zoned ? std::min(b.length_mm, v) : 0.0;
  head_r_[sb] = zoned ? rj : 1.0;
  head_rd_[sb] = zoned ? rjd : 1.0;
  refresh_pieces(sb);
  update_r(index_b);
  resigma(z.walk[z.n_walk - 1].index, index_b);
  if (v < (g != kNone ? caps_[g].v : kInf)) {
    insert_joint_cap(sa, sb, z.j_mm, a.length_mm, v);
    if (prev_.valid && prev_.index_a == ia) prev_.vg = std::min(prev_.vg, v);
  }
  return true;
}

void AccelLimitedAccDec::joint_zones(std::uint64_t index_a, std::size_t slot_b, const Segment& b) {
  const LastZone zone_before = last_zone_;
  last_zone_.valid = false;
  const Segment& a = buf_[index_a];
  const std::size_t sa = buf_.slot(index_a);
  // (Directions and corner speed from the kernel when it computed them for this joint.)
  const bool given = corner_index_a_ == index_a;
  const AxisVec e = given ? corner_e_ : a.end_direction();
  const AxisVec s = given ? corner_s_ : b.start_direction();
  const AxisVec a_start = a.start_direction();  // (on_joint() needs it too)
  const double r_ab = std::min(ratio_[sa], ratio_[slot_b]);
  // A pair of steps around the joint changes speed by up to the r of either side: an increase
  // by the r where step 2 goes (all in b when the sample is on the joint), a decrease by the r
  // of step 1 (all in a). So the larger of both must fit in the other's direction too.
  const double r_hi = std::max(ratio_[sa], ratio_[slot_b]);
  const double around = std::max(vcap_[sa], vcap_[slot_b]);  // as in on_joint
  const double corner = given ? corner_pc_ : planner::joint_speed_pc(a, b, lim_, false);
  corner_index_a_ = ~std::uint64_t{0};
  double v0 = std::min(around, corner);
  // After a capped joint close before (at a's start, chained; no filter) the tool cannot be
  // faster here than it can get from that cap: ≤ √(Vp² + 2·A0·d) + 2·A0 within d of it
  // (accelerating from ≤ Vp, or braking towards it, 3.), d ≤ L_a + 2V over the zone. A short
  // segment between a sharp and a gentle corner otherwise got the gentle one's zone sized for
  // the segments' caps (0.1 mm of line-contouring-xz braked at 0.22·A for a 3.6 µm segment).
  // Used as V it becomes this joint's cap (on_joint), so the zone's premise holds either way.
  // Also at a joint with no cap of its own (a gentle turn the top speed passes): its zone, sized
  // for the segments' caps, reached 2·V_top back over the braking for the corner before it
  // (0.33 mm at 0.3·A0 before a 30° corner of line-contouring-xz: 22.061 → 22.023 s).
  if (lag_ == 0 && prev_.valid && prev_.index_b == index_a) {
    const double vp = prev_.vg / 0.999;  // its cap, or the caps around it when it had none
    double v = v0;
    for (int it = 0; it < 8; ++it) {
      const double reach = std::sqrt(vp * vp + 2 * a0_ * (a.length_mm + 2 * v)) + 2 * a0_;
      if (reach >= v) break;
      v = reach;
    }
    // (A joint without a cap gets one only where its turn at the top speed takes a quarter of
    // A0 or more, between segments of a step or more: a cap at every joint of tiny segments,
    // several per cycle, each entering and leaving the trees, cost stress_test 40 % of its step
    // rate, and at the straight joints of long merged lines 20 %.)
    double turn = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) turn = std::max(turn, std::abs(s[i] - e[i]));
    if (corner < around ||
        (around * turn >= 0.25 * a0_ && a.length_mm >= 2 * v && b.length_mm >= v)) {
      v0 = v;
    }
  }
  // At gentle corners the segments' caps (the machine's top speed) are far above a CAM
  // program's feed, and the zone sized for them let the speed change by little more than the
  // floor's share (bench/README (c)). Sized for F instead, with a joint cap of F so that it
  // holds at any override: F the highest feed of the segments the pairs around the joint can
  // start in, [j − (2 + reach_lag)·V, j + V] (b at least V long, the walk back over at most
  // kZoneWalk segments ahead of the tool's), so that at ≤ 100 % the cap costs nothing. Only
  // where that leaves the speed change more room (below). Sizing for OR_max·F without a cap
  // instead changed nothing on the built-in machine (200 % of F 6 000 is above its top speed).
  const double v_feed = [&] {
    double vf = std::max(a.feed_pc, b.feed_pc);
    if (!(b.length_mm >= vf)) return kInf;
    double from = a.s0_mm;
    std::size_t walked = 0;
    for (std::uint64_t k = index_a; from > a.end_mm() - (2 + reach_lag_) * vf;) {
      if (k <= std::max(cur_, buf_.begin_index())) return kInf;  // the tool's segment
      const Segment& x = buf_[--k];
      if (x.kind != ItemKind::kMotion) {
        if (x.barrier) break;  // a stop: no step crosses it
        continue;
      }
      if (++walked > kZoneWalk) return kInf;
      vf = std::max(vf, x.feed_pc);
      from = x.s0_mm;
    }
    return vf;
  }();
  // Arcs next to the joint: a step of length u on an arc of curvature κ leaves its tangent's
  // line by R(1 − cos φ) ≤ u²κ/2 along the normal N (φ = uκ) and falls short along it by
  // u − R sin φ ≤ u³κ²/6; N turns by ≤ uκ over the step. Per axis ≤ (u²κ/2)(|N_i| + uκ·h_i)
  // + u³κ²/6 (h_i: the axis' share of the arc plane), from each side (7.).
  struct ArcSide {
    double k = 0;                    // curvature 1/ρ; 0: not an arc
    std::array<double, 3> n{}, h{};  // |N_i| at the joint, the axis' share of the plane
  };
  auto arc_side = [](const Segment& x, double phi) {
    ArcSide side;
    if (!x.arc || x.rho_mm <= 0) return side;
    side.k = 1.0 / x.rho_mm;
    const Vec3 nrm = std::cos(phi) * x.e1 + std::sin(phi) * x.e2;
    for (std::size_t i = 0; i < 3; ++i) {
      side.n[i] = std::abs(component(nrm, i));
      side.h[i] = std::hypot(component(x.e1, i), component(x.e2, i));
    }
    return side;
  };
  const ArcSide side_a = arc_side(a, a.sweep_rad), side_b = arc_side(b, 0.0);
  auto sag = [](const ArcSide& x, double v, std::size_t i) {
    if (x.k == 0 || i >= 3) return 0.0;
    const double k = x.k;
    return 0.5 * v * v * k * (x.n[i] + v * k * x.h[i]) + v * v * v * k * k / 6.0;
  };
  // Headroom per axis left by the turn at speed v (7.): with both steps ≤ V and |u2 − u1| ≤ D
  // the worst second differences are V·(S_i − E_i) − D·S_i, V·(S_i − E_i) + D·E_i, D·S_i and
  // D·E_i, each plus the arcs' sag; the largest D meeting all (< 0: the turn alone is too much).
  // A chain of short segments (the tangent's spread over the window before the joint,
  // planner/turn_window.hpp, beyond this corner's own turn): a pair of steps ≤ V whose window
  // ends here sees |Δu|·|e_i| + V·T_i on axis i (e_i the tangent somewhere in the window, ≤ its
  // largest |e_i|) and |Δu| + V·T as a whole; T taken at the kernel's speed, ≥ every V used
  // here (a shorter window has no more spread).
  const planner::Turn chain_turn = given ? corner_turn_ : planner::Turn{};
  const bool chained = [&] {
    double own2 = 0;
    for (std::size_t i = 0; i < kMaxAxes; ++i) own2 += (s[i] - e[i]) * (s[i] - e[i]);
    // (A spread beyond the corner's own that adds less than 0.01 % of A0 at the corner speed,
    // the wobble of a line cut into pieces with rounded coordinates, is left to the margins.)
    return (chain_turn.total - std::sqrt(own2)) * corner > 1e-4 * a0_;
  }();
  // A decrease (u2 < u1) meets only the first vertex and D·|S_i|, D·|E_i| ≤ a_i (its extremes
  // over c ∈ [0, u1] are u2·S − u1·E and (u2 − u1)·S), an increase only the second (c ∈
  // [u1 − u2, u1]: u2·S − u1·E and (u2 − u1)·E): decreases_only gives the decrease's D.
  auto d_max = [&](double v, bool decreases_only = false) {
    double d = r_hi * a0_;
    if (chained) {
      if (v * chain_turn.total > a0_) return -1.0;
      d = std::min(d, a0_ - v * chain_turn.total);
    }
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      const double ai = lim_.axis_amax_pc2[i] - sag(side_a, v, i) - sag(side_b, v, i);
      if (chained) {
        const double tc = v * chain_turn.axis[i];
        if (tc > ai) return -1.0;
        const double m = chain_turn.top[i];  // the largest |tangent_i| in the window
        if (m > 1e-12) d = std::min(d, (ai - tc) / m);
      }
      const double t = v * (s[i] - e[i]);
      if (std::abs(t) > ai) return -1.0;
      if (std::abs(s[i]) > 1e-12) {
        d = std::min(d, std::min(ai, ai + (s[i] > 0 ? t : -t)) / std::abs(s[i]));
      }
      if (std::abs(e[i]) > 1e-12) {
        d = std::min(
            d, (decreases_only ? ai : std::min(ai, ai - (e[i] > 0 ? t : -t))) / std::abs(e[i]));
      }
    }
    return d;
  };
  double d = d_max(v0);
  // Only where the feed leaves the speed change more room than the passing speed does (at
  // 100 % the cap then costs nothing; where the zone allows the segments' r anyway it would
  // only add a cap that holds the corner at F above 100 %).
  if (v_feed < v0) {
    const double d_feed = d_max(v_feed);
    if (d_feed > 1.001 * d) {
      v0 = v_feed;
      d = d_feed;
    }
  }
  // Forward, what the caps before can leave here (13.'s counterpart): from a cap vc at j_c the
  // tool accelerating at A0 reaches about √(vc² + 2·A0·(j − j_c)) at j (the discrete steps
  // vc + k·A0 land below it: u_k² = vc² + 2·A0·D_k − k·A0²); the minimum over the caps before
  // is kept as one running square (reach_sq_, + 2·A0·L per segment, reset where the joints are
  // not consecutive). Sized and capped there where that gives the zone ≥ 20 % more room for the
  // speed change (a choice, as in 13.: the cap makes it hold; A0/2 below it, as 13. takes,
  // slowed vcarve by 1.4 s). Only at joints with a corner cap of their own, between lines,
  // without a filter. circle_small_segments 12.435 → 12.276 s.
  const double reach_sq = reach_b_ == index_a ? reach_sq_ + 2 * a0_ * a.length_mm : kInf;
  if (lag_ == 0 && reach_sq < kInf && corner < around && !a.arc && !b.arc) {
    const double v_r = std::sqrt(reach_sq);
    if (v_r < v0 && v_r > 0) {
      const double d_r = d_max(v_r);
      if (d_r >= kRezoneGain * std::max(d, kZoneFloor * r_ab * a0_)) {
        v0 = v_r;
        d = d_r;
      }
    }
  }
  double vj = v0;
  const double floor = kZoneFloor * r_ab * a0_;
  if (d < floor) {
    // Too little left: the corner is passed slower instead, so that Δu ≤ floor fits. Without
    // the sag the bound is linear in V: |V·Δ_i − F·S_i| ≤ a_i and |V·Δ_i + F·E_i| ≤ a_i
    // (Δ = S − E, F = floor; true at V = 0); the sag, growing with V, is then met by bisection.
    d = floor;
    for (std::size_t i = 0; i < kMaxAxes; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      const double delta = s[i] - e[i];
      if (std::abs(delta) <= 1e-12) continue;
      const double sg = delta > 0 ? 1.0 : -1.0, ai = lim_.axis_amax_pc2[i];
      vj = std::min(vj, (ai + d * s[i] * sg) / std::abs(delta));
      vj = std::min(vj, (ai - d * e[i] * sg) / std::abs(delta));
    }
    vj = std::max(vj, 0.0);
    if (d_max(vj) < floor) {
      double lo = 0, hi = vj;  // d_max(0) ≥ floor: r_ab·A0·|S_i|, r_ab·A0·|E_i| ≤ a_i
      for (int it = 0; it < 40; ++it) (d_max(0.5 * (lo + hi)) >= floor ? lo : hi) = 0.5 * (lo + hi);
      vj = lo;
    }
  }
  // The speed decreases' D at the speed the zone is sized for (vj: v0, or lowered to the floor;
  // a smaller V keeps it, convex in V and true at V = 0), ≥ d; chains below lower it too.
  double d_dec = std::max(d, d_max(vj, true));
  // Two or three corners within one step (a and the segment x before it shorter than the step,
  // on_joint()): a pair of steps may turn from x's end (or the end of the one before x) to b at
  // once while the speed changes. Its zone: d also meets 7.'s vertices for that turn at the
  // chain's V (chain_d_max()), over [c − 2V, j + V] (c the chain's first corner, so the zone
  // reaches back over the middle segments too). Where that leaves less than the floor, the
  // chain is passed slower (chain_speed_pc(), the cap of both joints) or, below the middle's
  // length, at most that (no step then skips a middle segment, and each corner's own zone
  // holds). The turn alone at the chain's V used the whole axis budget before: 1 407 mm/s² on
  // a 1 400 axis over a 1.3 µm line between two corners.
  zone_chain_vg_ = kInf;
  double chain_mm = 0;
  double r_top = r_hi;
  if (prev_.valid && prev_.index_b == index_a && a.length_mm < vj && !straight_joint(e, s)) {
    const double xr = prev_.index_a >= buf_.begin_index() ? ratio_[buf_.slot(prev_.index_a)] : 1.0;
    r_top = std::max(r_hi, xr);
    ChainMid mids[2] = {
        {prev_.a_start_dir, prev_.end_dir, prev_.a_len_mm, prev_.a_sweep_rad},
        {a_start, e, a.length_mm, a.arc && a.rho_mm > 0 ? a.length_mm / a.rho_mm : 0.0}};
    auto chain = [&](const AxisVec& from, const ChainMid* m, std::size_t n, double v_in) {
      double mid_mm = 0;
      for (std::size_t k = 0; k < n; ++k) mid_mm += m[k].len_mm;
      const double vc = std::min(v_in, planner::turn_speed_pc(from, s, lim_));
      if (!(vc > mid_mm)) return;  // steps ≤ the middle: each corner's own zone holds
      chain_mm = std::max(chain_mm, mid_mm);
      const double dc = chain_d_max(from, s, m, n, vc, r_top * a0_, lim_);
      if (dc >= floor) {
        d = std::min(d, dc);
        d_dec = std::min(d_dec, dc);
        return;
      }
      const double vf = chain_speed_pc(from, s, m, n, floor, lim_);
      if (vf > mid_mm) {
        zone_chain_vg_ = std::min(zone_chain_vg_, vf);
        const double df = std::max(floor, chain_d_max(from, s, m, n, vf, r_top * a0_, lim_));
        d = std::min(d, df);
        d_dec = std::min(d_dec, df);
      } else {
        zone_chain_vg_ = std::min(zone_chain_vg_, mid_mm);
        d_dec = d;  // (each corner's own zone: the joint's d)
      }
    };
    if (!straight_joint(prev_.end_dir, a_start)) {
      chain(prev_.end_dir, &mids[1], 1, std::min(prev_.vg, vj));
    }
    if (prev_.short_a && !straight_joint(prev_.end_dir2, prev_.a_start_dir)) {
      chain(prev_.end_dir2, mids, 2, std::min({prev_.vg2, prev_.vg, vj}));
    }
    vj = std::min(vj, zone_chain_vg_);
  }
  // A chain's zone must reach back over [j − (2 + reach_lag)·V, j]; the walk below covers at most
  // kZoneWalk segments, so where they are shorter the chain is passed slower instead.
  if (chained && d < r_top * a0_) {
    double from = a.end_mm();
    std::size_t walked = 0;
    bool limited = false;
    for (std::uint64_t k = index_a + 1; k-- > std::max(cur_, buf_.begin_index());) {
      if (!buf_.is_motion(k)) {
        if (buf_[k].barrier) break;
        continue;
      }
      if (walked == kZoneWalk) {
        limited = true;
        break;
      }
      from = buf_[k].s0_mm;
      ++walked;
      if (from <= a.end_mm() - (2 + reach_lag_) * vj) break;
    }
    if (limited) vj = std::min(vj, (a.end_mm() - from) / (2 + reach_lag_));
  }
  // The joint's cap: the passing speed, or lower where the floor or a chain needs it.
  const double cap_v = std::min(vj, zone_chain_vg_);
  // 13. This joint's cap bounds the speed over the zone of the joint before it.
  if (lag_ == 0) {
    const double vc = std::min({corner, around, cap_v});
    if (vc < 0.999 * around) rezone_before(zone_before, index_a, vc);
    reach_sq_ = std::min(reach_sq, vc * vc);
    reach_b_ = index_a + 1;
  }
  zone_vg_ = cap_v;
  zone_joint_pc_ = corner;
  zone_index_a_ = index_a;
  zone_e_ = e;
  zone_s_ = s;
  zone_a_start_ = a_start;
  const double rj = std::max(d / a0_, 1e-6);
  // σ's r (decreases, 3. (ii)): without a filter only (with one, the output averages both).
  const double rjd = lag_ == 0 ? std::max(rj, d_dec / a0_) : rj;
  // Every step within V of the joint is ≤ V: the joint cap's Vg when there is one, else the
  // segments' caps.
  const double v = std::min(cap_v < 0.999 * around ? cap_v : around, v_feed);
  const double zone_from = a.end_mm() - (2 + reach_lag_) * v - chain_mm;
  if (late_check_ && !late_hold_) {
    // The block's range caps and the joint cap on_joint() will set (6.), with σ(c) no higher
    // than the zone below leaves it (r ≥ min(r_lo, r_j) over [zone start, c]).
    Cap joint_cap{0, 0, 0, 0, false, false};
    const double vg = std::min({corner, around, cap_v});
    if (vg < 0.999 * around) {
      const double w = vg * (1 + cap_lag_);
      joint_cap = {a.end_mm() - w, a.end_mm() + w, vg, 0, false, vg >= a0_};
    }
    check_late(a.end_mm(), std::max(zone_from, pos_mm_), rj < r_hi ? rj : 1,
               vg < 0.999 * around ? &joint_cap : nullptr, index_a);
    if (!late_hold_ && rj < r_hi && step_ > 0) {
      // The zone also lowers σ between the tool and the stop it brakes for: that stop's lattice
      // bound (3.) must still allow the last step. Taken at the joint, not at b's end: a hold
      // that on_joint()'s cap for two corners in one cycle may still start (insert()) keeps the
      // stop there (found: 2 011.7 mm/s² with a 1 µm segment between a reversal and 8°).
      const double zs = std::max(zone_from, pos_mm_);
      const double sigma_j = std::min(
          sigma_at(a.end_mm()), sigma_at(zs) + std::min(rj, r_zone_.min()) * (a.end_mm() - zs));
      const double d_sigma = std::max(0.0, sigma_j - late_sigma_p_);
      if (std::sqrt(a0_ * a0_ / 4 + 2 * a0_ * d_sigma) - a0_ / 2 < step_) start_hold(a.end_mm());
      // And the landing bounds in real distance, which take the zones' r (3.).
      check_stop(b.end_mm(), a.end_mm(), std::min(rj, ratio_[slot_b]));
    }
  }
  if (rj >= r_top) return;  // the segments' own r already fits (rjd ≥ rj)
  // The zone [j − 2V, j] may reach back over several short segments (at most kZoneWalk): each
  // gets it as (part of) its tail zone. Never under or behind the tool (σ there is in use; a
  // late joint, see 6.).
  // (While a late block is held the tool stops at hold_mm_: no zone behind it.)
  const double zone_start = std::max(zone_from, late_hold_ ? hold_mm_ : pos_mm_);
  std::uint64_t first = index_a + 1;
  std::size_t walked = 0;
  std::array<WalkedTail, kRezoneWalk> walk{};
  for (std::uint64_t k = index_a + 1;
       k-- > std::max(cur_, buf_.begin_index()) && walked < kZoneWalk;) {
    const Segment& x = buf_[k];
    if (x.kind != ItemKind::kMotion) {
      if (x.barrier) break;
      continue;
    }
    if (x.end_mm() <= zone_start) break;
    const std::size_t sx = buf_.slot(k);
    const double covered = x.end_mm() - std::max(zone_start, x.s0_mm);
    if (walked < kRezoneWalk) walk[walked] = {k, tail_mm_[sx], tail_r_[sx], tail_rd_[sx]};
    if (tail_mm_[sx] > 0) {
      tail_r_[sx] = std::min(tail_r_[sx], rj);
      tail_rd_[sx] = std::min(tail_rd_[sx], rjd);
    } else {
      tail_r_[sx] = rj;
      tail_rd_[sx] = rjd;
    }
    tail_mm_[sx] = std::max(tail_mm_[sx], covered);
    refresh_pieces(sx);
    update_r(k);
    first = k;
    ++walked;
  }
  const double head = (1 + reach_lag_) * v;
  add_head(slot_b, std::min(b.length_mm, head), rj, rjd);
  // (A plain zone, or a chain's: the walk covered it whole, over motion items only.)
  if (lag_ == 0 && !a.arc && !b.arc && !chained && walked >= 1 && walked <= kRezoneWalk &&
      first + walked == index_a + 1 && zone_start == zone_from && zone_from >= buf_[first].s0_mm) {
    last_zone_ = {true, index_a, a.end_mm(), v, r_hi, r_top, floor, e, s, walk, walked, chain_mm};
  }
  if (lag_ > 0 && head > b.length_mm) carry(a.end_mm() + head, rj);
  if (first > index_a) return;
  resigma(first, index_a);
}

double AccelLimitedAccDec::brake(double k, double sigma_p) const {
  return std::sqrt(std::max(0.0, a0_ * a0_ + k - 2 * a0_ * sigma_p)) - a0_;
}

double AccelLimitedAccDec::lattice(double k, double sigma_p) const {
  return std::max(0.0, std::sqrt(std::max(0.0, k - 2 * a0_ * sigma_p)) - 0.5 * a0_);
}

std::size_t AccelLimitedAccDec::level_of(double or_ratio) const {
  if (or_ratio != level_or_) {
    level_or_ = or_ratio;
    level_ =
        std::min(levels_ - 1, static_cast<std::size_t>(std::floor(or_ratio / level_step_ + 1e-9)));
  }
  return level_;
}

double AccelLimitedAccDec::feed_bound(double or_ratio, double sigma_p) const {
  // min(OR·F of the active feed caps, the braking bound of the level's feed keys): the braking
  // bound is ≥ OR·F, and left out, when its root's argument is ≥ (OR·F + A0)² (see step()).
  const double active = or_ratio * active_feed_.min();
  const double k = key_feed_.min(level_of(or_ratio));
  if (k == kInf) return active;
  if (active > 0 && active < kInf && a0_ * a0_ + k - 2 * a0_ * sigma_p >= above(active + a0_)) {
    return active;
  }
  return std::min(active, brake(k, sigma_p));
}

double AccelLimitedAccDec::arc_brake_step(std::size_t slot, const Segment& arc, double or_ratio,
                                          bool feed, ArcTarget& at) const {
  // 9. The caps ahead, all starting at or after e: the target speed W at e (their braking
  // bounds there, 3.), then the arc's braking curve back from e.
  const double e = std::min(arc.end_mm() - tail_mm_[slot], entry_.min());
  if (!(e > pos_mm_)) return 0;
  const double sigma_e = sigma0_[slot] + seg_sigma(slot, e - arc.s0_mm);
  double w = kInf;
  if (feed) {
    if (const double k = key_feed_.min(level_of(or_ratio)); k != kInf) w = brake(k, sigma_e);
  } else {
    if (const double k = key_geo_.min(); k != kInf) w = std::min(w, brake(k, sigma_e));
    if (const double k = key_lattice_.min(); k != kInf) w = std::min(w, lattice(k, sigma_e));
  }
  at = {e, sigma_e, w};
  const double rho = arc_rho_[slot];
  // g'² = g²·min(0.98², 1 − 2.5·φ − 12·φ²), φ = V_b/ρ the arc's largest angle per cycle (10.).
  const double phi = vcap_[slot] / rho;
  const double g = arc_g_[slot] * std::sqrt(std::min(kRecoverShare * kRecoverShare,
                                                     1 - 2.5 * phi - 12 * phi * phi));
  const double q_top = rho * g;  // v² where the normal acceleration alone is g'
  if (!(g > 0) || w == kInf || w * w >= q_top) return 0;
  // a(q) = min(A_c, √(g'² − (q/ρ)²)): A_c below q*, the circle law above.
  const double a_c = std::min(a0_, lin_r_[slot] * a0_);
  const double q_star = rho * std::sqrt(std::max(0.0, g * g - a_c * a_c));
  const double w2 = w * w;
  const double d_star = w2 < q_star ? (q_star - w2) / (2 * a_c) : 0.0;
  const double theta0 = std::asin(std::max(w2, q_star) / q_top);
  constexpr double kQuarter = 1.5707963267948966;
  // Q(p): the largest v² at p from which braking at a(v) reaches ≤ W at e; dQ/dp = −2·a.
  auto q_at = [&](double p, double& slope) {
    const double d = e - p;
    if (d <= 0) {
      slope = 0;
      return w2;
    }
    if (d <= d_star) {
      slope = -2 * a_c;
      return w2 + 2 * a_c * d;
    }
    const double th = theta0 + 2 * (d - d_star) / rho;
    if (th >= kQuarter) {
      slope = 0;
      return q_top;
    }
    slope = -2 * g * std::cos(th);
    return q_top * std::sin(th);
  };
  // The step x with x² = Q(pos + x): f(x) = x² − Q(pos + x) is increasing, and convex up to
  // e − pos (Q is concave there); beyond it Q = W², so the root is W when e − pos < W.
  if (e - pos_mm_ < w) return w;
  // Newton from a point with f ≥ 0 inside [0, e − pos] (f(e − pos) = (e − pos)² − W² ≥ 0, and
  // f(√Q(pos)) ≥ 0) stays above the root there; the result is accepted only with f ≤ 0.
  double slope = 0;
  double x = std::min(e - pos_mm_, std::sqrt(q_at(pos_mm_, slope)));
  for (int it = 0; it < 30; ++it) {
    const double f = x * x - q_at(pos_mm_ + x, slope);
    if (!(f > 0)) break;
    const double dx = f / (2 * x - slope);
    x -= dx;
    if (!(dx > 1e-13 * x)) break;
  }
  x *= 1 - 1e-9;  // just below the root
  return x > 0 && x * x <= q_at(pos_mm_ + x, slope) ? x : 0.0;
}

AccelLimitedAccDec::Bounds AccelLimitedAccDec::bound(double or_ratio, double sigma_p) const {
  auto brake_or_inf = [&](double k) { return k == kInf ? kInf : brake(k, sigma_p); };
  const std::size_t level = level_of(or_ratio);
  const double k_lat = key_lattice_.min();
  const double lat = k_lat == kInf ? kInf : lattice(k_lat, sigma_p);
  const double geo = std::min({active_geo_.min(), brake_or_inf(key_geo_.min()), lat});
  const double feed = std::min(or_ratio * active_feed_.min(), brake_or_inf(key_feed_.min(level)));
  return {geo, feed};
}

double AccelLimitedAccDec::reference_bound(double or_ratio) const {
  // Independent of the trees and of the cap states: every cap decides by position.
  double sigma_p = sigma_total_;
  if (!buf_.empty() && cur_ >= buf_.begin_index() && cur_ < buf_.end_index() &&
      buf_[cur_].kind == ItemKind::kMotion) {
    const Segment& s = buf_[cur_];
    const std::size_t slot = buf_.slot(cur_);
    sigma_p = sigma0_[slot] + seg_sigma(slot, pos_mm_ - s.s0_mm);
  }
  const std::size_t level =
      std::min(levels_ - 1, static_cast<std::size_t>(std::floor(or_ratio / level_step_ + 1e-9)));
  double out = kInf;
  for (std::size_t i = 0; i < caps_.size(); ++i) {
    if (state_[i] == State::kEmpty) continue;  // by id: every live cap once
    const Cap& c = caps_[i];
    if (pos_mm_ >= c.e_mm) continue;
    if (pos_mm_ >= c.entry) {
      out = std::min(out, c.feed ? or_ratio * c.v : c.v);
    } else if (c.lattice) {
      const double h = c.v - 0.5 * a0_;
      const double k = h * h + 2 * a0_ * c.sigma_c;
      out =
          std::min(out, std::max(0.0, std::sqrt(std::max(0.0, k - 2 * a0_ * sigma_p)) - 0.5 * a0_));
    } else {
      const double v = c.feed ? static_cast<double>(level) * level_step_ * c.v : c.v;
      const double k = v * v + 2 * a0_ * c.sigma_c;
      out = std::min(out, std::sqrt(std::max(0.0, a0_ * a0_ + k - 2 * a0_ * sigma_p)) - a0_);
    }
  }
  return out;
}

double AccelLimitedAccDec::pair_rise(const Segment& s) const {
  // 12. A pair across one joint between two lines. The zones (7.) hold every pair within
  // [j − 2V, j + V] to r_j, sized for the joint's passing speed V and for any sample position;
  // on paths whose corners lie a few steps apart they cover the whole path, and the speed
  // rises at the floor between corners that are passed far below their caps. For an increase
  // the exact limit is known here: u1 (the step just taken) and the joint j. With the pair
  // spanning j alone (the step before started in a, the next one cannot leave b), 7.'s
  // second difference at the tool for u2 = u1 + D is (u2 − u1)·S + c·(S − E),
  // c ∈ [u1 − u2, u1], linear in c: its extremes are D·E (within a's r) and u2·S − u1·E, so
  //     |u1·(S_i − E_i) + D·S_i| ≤ a_i  on every axis,  D ≤ min(r_a, r_b)·A0,
  // an interval of D that holds 0 when the tool's last pair did (u1 met the cap). Tangential:
  // D ≤ A0; normal: the step crossing j and the one beside it are ≤ Vg (the joint's cap, or 9.'s
  // exact limit). Decreases keep the zones' r (σ, the braking bounds, 3.): only the rise
  // changes. Returns 0 where this does not apply (the zones' r stays).
  const double u1 = step_;
  const double from = pos_mm_ - u1, to = pos_mm_ + u1 + a0_;
  const bool behind = from < s.s0_mm, ahead = to >= s.end_mm();
  if (behind == ahead) return 0;  // none (the line's own rise above) or two joints
  const std::uint64_t ia = behind ? cur_ - 1 : cur_, ib = ia + 1;
  if (ia < buf_.begin_index() || ib >= buf_.end_index()) return 0;
  const Segment& a = buf_[ia];
  const Segment& b = buf_[ib];
  if (a.kind != ItemKind::kMotion || b.kind != ItemKind::kMotion || a.arc || b.arc) return 0;
  if (a.s0_mm > from || b.end_mm() <= to || a.end_mm() != b.s0_mm) return 0;
  const AxisVec e = a.end_direction(), sd = b.start_direction();
  double c = 0;
  if (!linear_turn_cos(e, sd, c)) return 0;
  constexpr double kMargin = 1 - 1e-6;
  double d = std::min(ratio_[buf_.slot(ia)], ratio_[buf_.slot(ib)]) * kMargin * a0_;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double ai = kMargin * lim_.axis_amax_pc2[i];
    const double t = u1 * (sd[i] - e[i]);
    if (std::abs(t) > ai) return 0;
    if (std::abs(sd[i]) <= 1e-12) continue;
    // −a_i ≤ t + D·S_i ≤ a_i: D ≤ (a_i − t)/S_i for S_i > 0, (−a_i − t)/S_i for S_i < 0.
    d = std::min(d, sd[i] > 0 ? (ai - t) / sd[i] : (-ai - t) / sd[i]);
  }
  return std::max(0.0, d);
}

double AccelLimitedAccDec::after_corner() {
  // The tool's segment b and the joint j at its start: the last step crossed j alone (it started
  // in the line a before j, recorded by step()), b is a line and j has a joint cap.
  const Crossed x = crossed_;
  crossed_.valid = false;
  if (!x.valid || buf_.empty() || cur_ < buf_.begin_index() || cur_ >= buf_.end_index()) {
    return kInf;
  }
  const Segment& b = buf_[cur_];
  const double j = b.s0_mm;
  if (b.kind != ItemKind::kMotion || b.arc || x.j_mm != j || !(j <= pos_mm_)) return kInf;
  const std::size_t sb = buf_.slot(cur_), cap_pos = 3 * sb + 2;
  if (pos_state(cap_pos) != State::kActive) return kInf;
  const AxisVec& e = x.e;
  const AxisVec sd = b.start_direction();
  double c = 0;
  if (!linear_turn_cos(e, sd, c)) return kInf;
  // Chords: d1 = α·E + β·S (the crossing, u1 = α + β), d2 = u2·S. With t = u2 − β:
  //   per axis |t·S_i − α·E_i| ≤ a_i,  tangential |u2 − u1| ≤ A0,
  //   normal a_n² = |d2 − d1|² − (|d2| − |d1|)² = 2·u2·(|d1| − β − α·c) ≤ A0²  (c = E·S; the
  //   quadratic terms cancel, |d1|² = α² + β² + 2αβc), and with a resultant limit
  //   |d2 − d1|² = t² − 2αc·t + α² ≤ A0². Each gives an interval of u2.
  constexpr double kMargin = 1 - 1e-6;
  const double alpha = j - x.from_mm, beta = pos_mm_ - j, u1 = alpha + beta;
  const double amax = kMargin * a0_;
  double lo = u1 - a0_, hi = u1 + amax;
  // The slowest step this cycle may take: u1 − ρ·A0, ρ the larger of the mean r over the
  // crossing (every braking bound allowed u1, 3. (ii)) and the r of b's piece at the tool (a
  // hold or an override decrease: step() keeps the zone's r for them in this cycle), as 11.
  const double rho = std::min(
      1.0,
      std::max((sigma0_[sb] + seg_sigma(sb, beta) - x.sigma_from) / u1, piece_r(sb, beta)) + 1e-12);
  const double slowest = u1 - rho * a0_;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double ai = kMargin * lim_.axis_amax_pc2[i];
    const double ae = alpha * e[i];
    if (std::abs(sd[i]) <= 1e-12) {
      if (std::abs(ae) > ai) return kInf;
      continue;
    }
    const double t1 = (ae - ai) / sd[i], t2 = (ae + ai) / sd[i];
    lo = std::max(lo, beta + std::min(t1, t2));
    hi = std::min(hi, beta + std::max(t1, t2));
  }
  const double d1 = std::sqrt(std::max(0.0, alpha * alpha + beta * beta + 2 * alpha * beta * c));
  const double bend = d1 - beta - alpha * c;
  if (bend > 0) hi = std::min(hi, amax * amax / (2 * bend));
  // At a fold (a reversal, c ≈ −1) the sample before j also lies on b, α past j: a reading of
  // the positions that takes it there measures the crossing as |β − α| = |d1|, so u2 − |d1| ≤ A0
  // too (found by the late-block property: 1.0 → 3.0 µm/cycle across a 1.5 µm G0 reversed,
  // read as 0.99 → 3.0, 2 010 mm/s²).
  if (c < -0.999) hi = std::min(hi, d1 + amax);
  if (lim_.bound_resultant) {
    const double disc = amax * amax - alpha * alpha * (1 - c * c);
    if (disc < 0) return kInf;
    lo = std::max(lo, beta + alpha * c - std::sqrt(disc));
    hi = std::min(hi, beta + alpha * c + std::sqrt(disc));
  }
  // d2 inside b (past b's end the next joint turns too): u2 ≤ u1 + A0 ≤ what is left of b. (A
  // shorter b is left to the cap: there the next corner's cap follows within a step or two, and
  // a faster step out of this one measured slower on the whole, 13.07 → 13.24 s on
  // circle_small_segments.)
  if (b.end_mm() - pos_mm_ < u1 + a0_) return kInf;
  // Every step the cycle may choose lies in [u1 − ρ·A0, the bounds]: the interval must hold its
  // lower end, or the cap stays.
  if (!(lo <= slowest && hi >= lo)) return kInf;
  clear(cap_pos);
  return hi;
}

bool AccelLimitedAccDec::centre_setup(std::size_t g, const Segment& a, const Segment& b,
                                      Centre& ct) const {
  const Cap& cap = caps_[g];
  ct.vg = cap.v;
  ct.j = b.s0_mm;
  ct.c_mm = cap.c_mm;
  ct.e = a.end_direction();
  ct.sd = b.start_direction();
  if (!linear_turn_cos(ct.e, ct.sd, ct.c)) return false;
  // Not at folds: there the checker may read the sample before j as lying after it (9.).
  if (ct.c < -0.5) return false;
  // The cycle after the step u0 takes u1 ≤ Vg (the cap is active from c = j − Vg on, and the
  // sample lands in [c, j)) and ≥ u0 − r_hi·A0: every bound but this cap's allowed u0 here, so
  // it allows u0 − (mean r over the step)·A0 there (3. (ii); the stop's bounds with a_stop ≤ the
  // r there), and a hold or an override decrease slows by r·A0. r_hi: the highest r over
  // [tool, j] (a's, or its tail zone's when the tool is inside it).
  const std::size_t sa = buf_.slot(cur_);
  ct.slot_a = sa;
  ct.a_s0 = a.s0_mm;
  ct.r_hi = ratio_[sa];
  if (pos_mm_ - a.s0_mm >= a.length_mm - tail_mm_[sa]) ct.r_hi = std::min(ct.r_hi, tail_r_[sa]);
  ct.r_lo = tail_mm_[sa] > 0 ? std::min(ratio_[sa], tail_r_[sa]) : ratio_[sa];
  return true;
}

double AccelLimitedAccDec::piece_r(std::size_t slot, double x_mm) const {
  // r_span() from here: the head's r while x < h, the tail's once the span reaches L − t.
  double rate = ratio_[slot];
  if (x_mm < head_mm_[slot]) rate = std::min(rate, head_r_[slot]);
  if (tail_mm_[slot] > 0 && x_mm >= len_mm_[slot] - tail_mm_[slot]) {
    rate = std::min(rate, tail_r_[slot]);
  }
  return rate;
}

double AccelLimitedAccDec::slowdown_r(std::size_t slot, double s0, double from_mm,
                                      double to_mm) const {
  // A step x ≤ every braking bound lets the next one be ≥ x − r̄·A0, r̄ = Δσ/x the mean r over
  // the step (3. (ii); the stop's lattice too, and its landing bounds take the lowest r up to
  // the stop, ≤ r̄). A hold or an override decrease slows by A0 × the r of the next step's
  // reach, ≤ the r of the piece it starts in. (1e-12: roundings of σ.)
  const double x0 = from_mm - s0, x1 = to_mm - s0;
  const double mean = x1 > x0 ? (seg_sigma(slot, x1) - seg_sigma(slot, x0)) / (x1 - x0) : 1.0;
  return std::min(1.0, std::max(mean, piece_r(slot, x1)) + 1e-12);
}

bool AccelLimitedAccDec::centred_ok(const Centre& ct, double from_mm, double u0) const {
  constexpr double kMargin = 1 - 1e-6;
  const double amax = kMargin * a0_;
  const double vg = ct.vg, c = ct.c;
  // The sample α before j between the step u0 (along E) and u1: the chords d0 = u0·E and
  // d1 = u1·E (u1 ≤ α) or α·E + β·S (β = u1 − α). Per axis |(α − u0)·E_i + β·S_i| ≤ a_i,
  // tangential |u1 − u0| ≤ A0 (path speeds), normal a_n² = 2·u0·(|d1| − α − β·c) ≤ A0² (as in
  // after_corner(), increasing in β), resultant |d1 − d0|² ≤ A0². Each is convex in u1 on
  // u1 ≤ α and on u1 ≥ α, so the ends of both pieces decide.
  auto sample_ok = [&](double alpha, double u1) {
    // (u0 − r·A0 at the low end: the deceleration every braking plan uses.)
    if (u1 - u0 > amax || u0 - u1 > a0_) return false;
    const double al = std::min(alpha, u1), beta = std::max(0.0, u1 - alpha);
    for (std::size_t i = 0; i < 3; ++i) {
      if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
      if (std::abs((al - u0) * ct.e[i] + beta * ct.sd[i]) > kMargin * lim_.axis_amax_pc2[i]) {
        return false;
      }
    }
    if (beta <= 0) return true;
    const double d1 = std::sqrt(std::max(0.0, al * al + beta * beta + 2 * al * beta * c));
    if (2 * u0 * (d1 - al - beta * c) > amax * amax) return false;
    if (lim_.bound_resultant) {
      const double w = al - u0;
      if (w * w + beta * beta + 2 * w * beta * c > amax * amax) return false;
    }
    return true;
  };
  const double p1 = from_mm + u0;
  const double alpha = ct.j - p1;
  // (Not within 10 nm of j: the checker takes a sample that close as reaching the joint.)
  if (!(alpha >= kMinAlphaMm) || p1 < ct.c_mm || u0 - vg > amax) return false;
  const double rho = slowdown_r(ct.slot_a, ct.a_s0, from_mm, p1);
  const double lo = std::max(0.0, std::min(vg, u0 - rho * a0_));
  if (!sample_ok(alpha, vg) || !sample_ok(alpha, lo)) return false;
  return !(alpha > lo && alpha < vg) || sample_ok(alpha, alpha);
}

double AccelLimitedAccDec::centred_top(const Centre& ct, double k_e, double k_s, double m_e,
                                       double m_s) const {
  // Per axis |k·x + m| ≤ a_i with k = k_e·E_i + k_s·S_i, m = m_e·E_i + m_s·S_i: the largest x.
  double top = kInf;
  for (std::size_t i = 0; i < 3; ++i) {
    if (!lim_.axis_on[i] || lim_.axis_amax_pc2[i] <= 0) continue;
    const double k = k_e * ct.e[i] + k_s * ct.sd[i], m = m_e * ct.e[i] + m_s * ct.sd[i];
    const double ai = (1 - 1e-6) * lim_.axis_amax_pc2[i];
    if (k > 1e-12) top = std::min(top, (ai - m) / k);
    if (k < -1e-12) top = std::min(top, (-ai - m) / k);
  }
  return top;
}

double AccelLimitedAccDec::centred_step(const Centre& ct, double u, double hi) const {
  // Every feasible step meets the per-axis limits with the crossing u1 = Vg, linear in u0:
  // (α − u0)·E + (Vg − α)·S with α = D − u0 (D = j − tool). Their largest u0 first.
  const double d = ct.j - pos_mm_;
  hi = std::min(hi, centred_top(ct, -2, 1, d, ct.vg - d));
  if (!(hi > u)) return u;
  return largest_ok(u, hi, [&](double x) { return centred_ok(ct, pos_mm_, x); });
}

double AccelLimitedAccDec::committing_step(const Centre& ct, double u, double hi,
                                           double& lo_next) const {
  // The step u_{-1} to p0 may exceed the cap's braking bound when from p0 the centred step
  // lo_next = u_{-1} − r_hi·A0 (the slowest the cycle at p0 can be made to go) is feasible.
  // lo_next = u_{-1} − ρ·A0 (the slowest the cycle at p0 can be made to go, ρ = slowdown_r()
  // of the step) is feasible.
  auto slowest = [&](double x) {
    return x - slowdown_r(ct.slot_a, ct.a_s0, pos_mm_, pos_mm_ + x) * a0_;
  };
  auto ok = [&](double x) {
    const double l = slowest(x);
    return l > 0 && ct.j - (pos_mm_ + x) > ct.vg && centred_ok(ct, pos_mm_ + x, l);
  };
  // The same per-axis limits from p0 = tool + x with u0 = x − ρ·A0: α − u0 = D + 2·ρ·A0 − 3x,
  // Vg − α = Vg − D − ρ·A0 + 2x; ρ between the lowest and the highest r up to j (a search
  // bound only: every answer is checked).
  const double d = ct.j - pos_mm_;
  auto top = [&](double ra) { return centred_top(ct, -3, 2, d + 2 * ra, ct.vg - d - ra); };
  hi = std::min(hi, std::max(top(ct.r_hi * a0_), top(ct.r_lo * a0_)));
  if (!(hi > u)) return u;
  const double best = largest_ok(u, hi, ok);
  if (best > u) lo_next = slowest(best);
  return best;
}

void AccelLimitedAccDec::step(const CycleInput& in) {
  advance_current();
  if (!held_cycle_) {
    if (lag_ > 0) {
      recent_[recent_pos_] = step_;  // (6.: the steps the filter may still hold)
      recent_pos_ = recent_pos_ + 1 == recent_.size() ? 0 : recent_pos_ + 1;
    }
    if (late_hold_) {
      // A held late block (6.) is released once the tool has been at rest at hold_mm_ for the
      // post filter's length (its output is then hold_mm_ too); until then hold_mm_ is a stop.
      rest_cycles_ = at_rest() ? rest_cycles_ + 1 : 0;
      const std::uint32_t settle = lim_.post_filter() ? lim_.post_cycles : 0;
      if (pos_mm_ >= hold_mm_ && rest_cycles_ > settle) release_hold();
      if (late_hold_ && in.stop_mm > hold_mm_) {
        CycleInput held = in;
        held.stop_mm = hold_mm_;
        held_cycle_ = true;
        step(held);
        held_cycle_ = false;
        return;
      }
    }
  }
  // Caps whose range the tool has entered, then caps it has left.
  while (entry_.min() <= pos_mm_) activate(entry_.argmin());
  // (release_ may hold an active cap's earlier end, ≤ its e: on_segment() extends caps without
  // a tree update; such a cap gets its current end and stays.)
  while (release_.min() <= pos_mm_) {
    const std::size_t g = release_.argmin();
    if (caps_[g].e_mm > pos_mm_) {
      release_.set(g, caps_[g].e_mm);
    } else {
      clear(where_[g]);
    }
  }

  // After a capped corner between lines: the exact limit of the step after the crossing (9.).
  const double after = lag_ == 0 && step_ > 0 ? after_corner() : kInf;

  double sigma_p = sigma_total_;
  double r = 1;
  // The tool's arc whose deceleration may follow its speed (5.); none: capacity.
  std::size_t recover_arc = buf_.capacity();
  // The tool's arc whose braking bounds may follow its speed (10.); none: capacity.
  std::size_t brake_arc = buf_.capacity();
  // The rise where the pair at the tool is a plain speed change along its line (0: none).
  double line_rise = 0;
  if (!buf_.empty() && cur_ < buf_.end_index() && buf_[cur_].kind == ItemKind::kMotion) {
    const Segment& s = buf_[cur_];
    const std::size_t slot = buf_.slot(cur_);
    sigma_p = sigma0_[slot] + seg_sigma(slot, pos_mm_ - s.s0_mm);
    // The lowest r over where the next step can go (the next segment, joint zones: 7.) — not
    // past a stop ahead: a segment after it with a lower r would make the landing lattice near
    // the stop switch to that r, a deceleration step of up to 1.5·A0 (found with the post
    // filter, whose exact-path corners are stops).
    double reach = pos_mm_ + step_ + a0_;
    // (A stop past the reach leaves it: the double below the stop is then ≥ reach.)
    if (in.stop_mm > pos_mm_ && in.stop_mm <= reach) {
      reach = std::min(reach, std::nextafter(in.stop_mm, pos_mm_));
    }
    const double r_reach = r_span(pos_mm_, reach, &reach_skip_);
    r = r_reach;
    // The last step started on this line and this one cannot leave it: the sample at the tool
    // turns nothing, so its speed may rise by the line's own r (a joint zone ahead within the
    // reach lowers r for the pairs whose sample is near the joint, 7.; no filter: 8. averages).
    if (lag_ == 0 && !s.arc && pos_mm_ - step_ >= s.s0_mm &&
        pos_mm_ + step_ + ratio_[slot] * a0_ < s.end_mm()) {
      line_rise = ratio_[slot] * a0_;
    } else if (lag_ == 0 && !s.arc && !in.hold && !lim_.bound_resultant &&
               !(in.stop_mm > pos_mm_ && in.stop_mm <= pos_mm_ + step_ + a0_)) {
      line_rise = pair_rise(s);
    }
    // Past the corner just crossed, its head zone (7.) is replaced by the exact limit: within
    // b before its tail zone, b's own r.
    // (Not for a hold or an override decrease: after_corner() counted on the zone's r for them.)
    if (after < kInf && reach < s.end_mm() - tail_mm_[slot] && !in.hold && !feed_recover_ &&
        !(in.or_ratio < prev_or_)) {
      r = ratio_[slot];
    }
    // Both steps of the pair inside the arc: the step before started in it too (a pair across
    // the joint before the arc is the joint zone's, 7., which counts on r).
    if (lag_ == 0 && arc_g_[slot] > 0 && reach < s.end_mm() && pos_mm_ - step_ >= s.s0_mm &&
        r_reach == ratio_[slot]) {
      recover_arc = slot;
    }
    // The pair of this step and the one before is inside the arc, or this step lands past the
    // point e where 9. hands over to the keys (then ≤ W, a step the keys allow).
    if (lag_ == 0 && arc_g_[slot] > 0 && pos_mm_ - step_ > s.s0_mm) brake_arc = slot;
  }
  // a: the speed change allowed in this cycle.
  const double a = r * a0_;

  // The cycle's step is a plain minimum, u = min(the change, the feed limit, the geometric caps,
  // the braking bounds, the stop bounds, to_stop), and a minimum does not change when a term
  // ≥ it is left out. So each braking or stop bound (a square root, the stop's landing step) is
  // computed only where it may be below the minimum of the cheap terms so far, t; otherwise a
  // test on squares shows that it is ≥ t (with a relative margin of kSkipMargin, far above the
  // rounding of either side: the skipped term, rounded, is > t). Same double as the full
  // computation (the order of a minimum does not matter; max(0, ·) below makes −0 and +0 one).
  // The feed bound is computed exactly: the override-decrease ramp compares against it.
  // The braking bound on the tool's arc with what the speed leaves (10.), computed only where a
  // braking bound is the binding term; each braking bound b becomes max(b, T).
  // (The geometric keys and the feed keys separately: after an override decrease the feed part
  // is left by the ramp of 5., the geometric part stays a hard limit.)
  double arc_t[2] = {-1, -1};
  ArcTarget arc_at[2];
  auto arc_brake = [&](bool feed) {
    const std::size_t i = feed ? 1 : 0;
    if (arc_t[i] < 0) {
      arc_t[i] = brake_arc < buf_.capacity()
                     ? arc_brake_step(brake_arc, buf_[cur_], in.or_ratio, feed, arc_at[i])
                     : 0.0;
    }
    return arc_t[i];
  };
  double feed_limit = feed_bound(in.or_ratio, sigma_p);
  const double feed_keys = feed_limit;  // without 10.
  if (brake_arc < buf_.capacity()) {
    const double active = in.or_ratio * active_feed_.min();
    if (feed_limit < active) feed_limit = std::min(active, std::max(feed_limit, arc_brake(true)));
  }
  if (check_) {
    const Bounds full = bound(in.or_ratio, sigma_p);
    last_bound_ = std::min(full.geo, full.feed);
    if (reference_bound(in.or_ratio) != last_bound_) ++mismatches_;
  }

  if (in.stop_mm != cached_stop_mm_) {
    cached_stop_mm_ = in.stop_mm;
    cached_stop_sigma_ = sigma_at(in.stop_mm);
  }
  const double to_stop = std::max(0.0, in.stop_mm - pos_mm_);
  const double d_sigma = std::max(0.0, cached_stop_sigma_ - sigma_p);

  // On an arc whose r was fixed for its top speed (a_n = 0.95·g there), a step below the top
  // leaves more for the tangent: rise by min(A0, √((0.98·g)² − (u⁺²/ρ)²)), u⁺ = this step plus
  // the most it may rise (inside the tool's arc, no joint zone in reach, no filter: as 5.).
  double rise = a;
  if (!in.hold && recover_arc < buf_.capacity()) {
    const std::size_t slot = recover_arc;
    const double most = std::min(a0_, lin_r_[slot] * a0_);
    const double u_hi = step_ + most;
    const double an = u_hi * u_hi / arc_rho_[slot];
    const double g = kRecoverShare * arc_g_[slot];
    rise = std::max(a, std::min(most, std::sqrt(std::max(0.0, g * g - an * an))));
  }
  rise = std::max(rise, line_rise);
  double u = in.hold ? step_ - a : step_ + rise;
  // Geometric caps and stops are hard limits, and so is the feed limit while the override has
  // not been lowered (following its bound needs no more than the deceleration of the zone just
  // run, 3. (ii) and 7.). After an override decrease the feed limit may drop by more than one
  // step's deceleration: then decelerate at a until the tool is within it again.
  if (in.or_ratio < prev_or_) feed_recover_ = true;
  prev_or_ = in.or_ratio;
  // On an arc r was fixed for its top speed, where a_n = v²/ρ leaves √(g² − a_n²) for the
  // tangent: slowing down for a lower override, the current step's a_n leaves more (inside the
  // tool's segment, no joint zone in reach, no filter after this type: 8. carries r).
  double a_recover = a;
  if (feed_recover_ && recover_arc < buf_.capacity()) {
    const std::size_t slot = recover_arc;
    const double an = step_ * step_ / arc_rho_[slot];
    // 2 % of g kept for the chords' discrete normal acceleration (the top-speed rule keeps 5 %).
    const double g = kRecoverShare * arc_g_[slot];
    const double at = std::sqrt(std::max(0.0, g * g - an * an));
    a_recover = std::max(a, std::min({a0_, lin_r_[slot] * a0_, at}));
  }
  // At least σ's mean r over the step just taken (no filter): the feed keys of the level before
  // the decrease allowed it, so they allow it less that mean·A0 now (3. (ii)). Decelerating at
  // a alone (the r over the next step's reach, lower in a joint zone than σ's r for decreases,
  // 7.) fell behind them: 50.26 mm/s at a 50 mm/s feed (RandomProgramsWithCoupledAxesAndLines).
  if (feed_recover_ && lag_ == 0 && step_ > 0) {
    a_recover = std::max(a_recover, std::clamp((sigma_p - prev_sigma_) / step_, 0.0, 1.0) * a0_);
  }
  const double feed = feed_recover_ ? std::max(step_ - a_recover, feed_limit) : feed_limit;
  // (Nested: an initializer list became a loop over a stack array; the same double, the first
  // of equal values as there.)
  u = std::min(std::min(std::min(std::min(u, feed), active_geo_.min()), to_stop), after);

  // The geometric braking bounds (3.): x ≤ √(A0² + K − 2·A0·σ) − A0 ≥ u when the root's
  // argument is ≥ (u + A0)²; lattice keys: x ≤ √(K − 2·A0·σ) − A0/2 ≥ u when K − 2·A0·σ ≥
  // (u + A0/2)².
  const bool skip = u > 0 && u < kInf;
  double geo_keys = kInf;  // the lowest geometric braking bound below u, without 10.
  const double k_geo = key_geo_.min();
  if (k_geo != kInf) {
    const double arg = a0_ * a0_ + k_geo - 2 * a0_ * sigma_p;
    if (!(skip && arg >= above(u + a0_))) {
      const double b = brake(k_geo, sigma_p);
      if (b < u) {
        geo_keys = b;
        u = std::min(u, std::max(b, arc_brake(false)));
      }
    }
  }
  const double k_lat = key_lattice_.min();
  if (k_lat != kInf) {
    const double arg = k_lat - 2 * a0_ * sigma_p;
    if (!(skip && arg >= above(u + 0.5 * a0_))) {
      const double b = lattice(k_lat, sigma_p);
      if (b < u) {
        geo_keys = std::min(geo_keys, b);
        u = std::min(u, std::max(b, arc_brake(false)));
      }
    }
  }

  // The stop: its σ lattice (≥ u when A0²/4 + 2·A0·Δσ ≥ (u + A0/2)²), the landing step in real
  // distance (≥ √(2·a·d) − a/2 for every m: d/(m + 1) + a·(m + 1)/2 ≥ √(2·a·d) by AM–GM, so
  // ≥ u when 2·a·d ≥ (u + a/2)²; d ≤ a returns d ≥ √(2·a·d) − a/2) and the tail cap V_t.
  // In real distance with the lowest r from the tool up to the stop, a_stop: with the r over the
  // next step's reach only, a lower r coming into reach would lower these bounds by more than
  // one step's deceleration at once (a 0.5 µm arc after a full circle at F 500: 8.3 → 6.8 →
  // 5.2 → 1.5 µm/cycle, 3 698 mm/s² on a 2 000 axis). The minimum over [tool, stop) only rises
  // as the tool moves on, and each bound rises with a, so following them stays within a_stop.
  // Computed only where the landing step with the window's lowest r may be below u.
  const double vt = tail_cap_pc_;
  const bool lattice_far = skip && u > 0 && a0_ * a0_ / 4 + 2 * a0_ * d_sigma >= above(u + a0_ / 2);
  auto landing_far = [&](double ac) {
    return 2 * ac * to_stop >= above(u + ac / 2) &&
           (to_stop <= vt ? vt >= u : ac * ac + vt * vt + 2 * ac * (to_stop - vt) >= above(u + ac));
  };
  double a_stop = a;
  bool stop_far = false;
  if (to_stop > 0 && !buf_.empty()) {
    // With the zones' r (3.; a block whose r or zone would lower these bounds at once is held,
    // 6.). (Both bounds rise with a where to_stop ≥ 2·V_t: far with the window's lowest r is far.)
    const double a_lo = std::min(a, r_zone_.min() * a0_);
    if (lattice_far && to_stop >= 2 * vt && landing_far(a_lo)) {
      stop_far = true;
    } else {
      a_stop = std::min(a, r_span(pos_mm_, std::nextafter(in.stop_mm, pos_mm_)) * a0_);
    }
  }
  if (!stop_far) stop_far = lattice_far && landing_far(a_stop);
  auto stop_bound = [&](double as) {
    double stop_limit = std::sqrt(a0_ * a0_ / 4 + 2 * a0_ * d_sigma) - a0_ / 2;
    stop_limit = std::max(stop_limit, std::min(to_stop, as));
    stop_limit = std::min(stop_limit, landing_step(to_stop, as));
    // The last V_t = min(A0, a_i)/2 before a stop (the lowest corner cap, a reversal) is run at
    // ≤ V_t: a joint cap that arrives late at a stop's position (the window's tail) then finds
    // the steps around it already within its cap (see 6.).
    if (to_stop > 0) {
      // In real distance with the local acceleration a (the cap lies within a few steps of the
      // stop; farther away the stop's own σ bound is the stricter one).
      const double tail =
          to_stop <= vt ? vt : std::sqrt(as * as + vt * vt + 2 * as * (to_stop - vt)) - as;
      stop_limit = std::min(stop_limit, tail);
    }
    return stop_limit;
  };
  if (!stop_far) u = std::min(u, stop_bound(a_stop));

  // 11. A capped corner between two lines just ahead, the step before its crossing: that step
  // may exceed the cap's braking bound when its sample keeps every limit for each crossing step
  // the next cycle may take; and the step before it too, when from there such a step remains
  // however the next cycle is slowed (committed: that cycle then takes one). A bounded few
  // evaluations, only in the two or three cycles before such a corner.
  const Commit commit = commit_;
  commit_.valid = false;
  // (Gated on the compact cap arrays first: the segments are loaded only near such a corner.)
  const std::size_t cp = cur_ + 1 < buf_.end_index() ? 3 * buf_.slot(cur_ + 1) + 2 : std::size_t{0};
  const std::uint32_t cg = cur_ + 1 < buf_.end_index() ? owner_[cp] : kNone;
  if (cg != kNone && lag_ == 0 && !jerk_on_ && (!in.hold || commit.valid) &&
      (u > 0 || commit.valid) && to_stop > 0 && cur_ >= buf_.begin_index() && !caps_[cg].feed &&
      pos_mm_ + caps_[cg].v < caps_[cg].c_mm + caps_[cg].v &&
      caps_[cg].c_mm + caps_[cg].v - pos_mm_ < 3 * caps_[cg].v + 3 * a0_) {
    const Segment& sa = buf_[cur_];
    const Segment& sb = buf_[cur_ + 1];
    const double j = sa.end_mm();
    const Cap& cap = caps_[cg];
    Centre ct;
    if (sa.kind == ItemKind::kMotion && sb.kind == ItemKind::kMotion && !sa.arc && !sb.arc &&
        sb.s0_mm == j && pos_mm_ - step_ >= sa.s0_mm && pos_mm_ + u < j &&
        std::abs(cap.c_mm + cap.v - j) <= 1e-9 * std::max(1.0, std::abs(j)) &&
        sb.length_mm >= cap.v + a0_ && centre_setup(cg, sa, sb, ct)) {
      const double first = in.hold ? step_ - a : step_ + rise;
      // The cycle's bound with this joint's cap left out (its key or its active leaf: two tree
      // updates), the stop's bounds included; above `want` it may answer min(bound, want).
      auto free_bound = [&](double want) {
        const bool active = state_[cg] == State::kActive;
        MinTree& t = active ? active_geo_ : (cap.lattice ? key_lattice_ : key_geo_);
        const double saved = t.at(cg);
        t.set(cg, MinTree::kEmpty);
        double f = std::min({first, feed, active_geo_.min(), to_stop, after});
        if (const double k = key_geo_.min(); k != kInf) f = std::min(f, brake(k, sigma_p));
        if (const double k = key_lattice_.min(); k != kInf) f = std::min(f, lattice(k, sigma_p));
        t.set(cg, saved);
        // The stop's bounds are ≥ x where far (the same tests as above, with x for u).
        const double x = std::min(f, want);
        const double a_lo = std::min(a, r_zone_.min() * a0_);
        const bool far = to_stop >= 2 * vt &&
                         a0_ * a0_ / 4 + 2 * a0_ * d_sigma >= above(x + a0_ / 2) &&
                         2 * a_lo * to_stop >= above(x + a_lo / 2) &&
                         a_lo * a_lo + vt * vt + 2 * a_lo * (to_stop - vt) >= above(x + a_lo);
        if (far) return x;
        const double as = std::min(a, r_span(pos_mm_, std::nextafter(in.stop_mm, pos_mm_)) * a0_);
        return std::min(f, stop_bound(as));
      };
      // What the step can be at most without that minimum (the search runs first, the minimum
      // only where the search found a step).
      const double pre = std::min({first, feed, to_stop, after});
      const double d0 = j - pos_mm_;
      const double top = ct.vg + (1 - 1e-6) * a0_;
      if (commit.valid && commit.j_mm == j && commit.from_mm == pos_mm_) {
        // Every bound but the cap's allows at least commit.lo here (3. (ii)), and the centred
        // step commit.lo was found feasible from here: the largest feasible one up to them.
        const double free = free_bound(std::min(top, d0));
        const double lo = std::min(commit.lo, free);
        u = in.hold ? (centred_ok(ct, pos_mm_, free) ? free : lo)
                    : centred_step(ct, lo, std::min({free, top, d0}));
      } else if (!in.hold && d0 < 2 * ct.vg + a0_) {
        double x = centred_step(ct, u, std::min({pre, top, d0}));
        if (x > u) {
          const double free = free_bound(x);
          if (x > free) x = centred_step(ct, u, std::min({free, top, d0}));
          u = x;
        }
      } else if (!in.hold) {
        double lo_next = 0;
        double x = committing_step(ct, u, std::min(pre, d0 - ct.vg), lo_next);
        if (x > u) {
          const double free = free_bound(x);
          if (x > free) x = committing_step(ct, u, std::min(free, d0 - ct.vg), lo_next);
          if (x > u) commit_ = {true, j, pos_mm_ + x, lo_next};
          u = x;
        }
      }
    }
  }
  u = std::max(0.0, u);
  if (u <= feed_limit) feed_recover_ = false;
  // A step above the keys' braking bounds follows 10.'s curve, whose e and W only blocks that
  // arrive in time may change: late_cap() holds a late block that would move them (6.).
  const bool geo_relied = arc_t[0] > 0 && u > geo_keys;
  const bool feed_relied = arc_t[1] > 0 && u > feed_keys;
  relied_e_mm_ = geo_relied ? arc_at[0].e_mm : feed_relied ? arc_at[1].e_mm : kInf;
  relied_sigma_e_ = geo_relied ? arc_at[0].sigma_e : arc_at[1].sigma_e;
  relied_w_geo_ = geo_relied ? arc_at[0].w : kInf;
  relied_w_feed_ = feed_relied ? arc_at[1].w : kInf;
  // A step from inside a line across its end: after_corner() looks at it in the next cycle.
  crossed_.valid = false;
  if (lag_ == 0 && !buf_.empty() && cur_ >= buf_.begin_index() && cur_ < buf_.end_index()) {
    const Segment& s = buf_[cur_];
    if (s.kind == ItemKind::kMotion && !s.arc && pos_mm_ >= s.s0_mm && pos_mm_ < s.end_mm() &&
        pos_mm_ + u >= s.end_mm()) {
      crossed_ = {true, s.end_mm(), pos_mm_, sigma_p, s.end_direction()};
    }
  }
  if (u > 0 && u >= to_stop) {
    pos_mm_ = in.stop_mm;  // land exactly on the stop
  } else {
    pos_mm_ += u;
  }
  prev_sigma_ = sigma_p;
  step_ = u;
  if (!jerk_on_) {
    tool_mm_ = pos_mm_;
    tool_step_ = u;
    return;
  }
  // Jerk stage (8.): the tool's step is the mean of the last T2 commanded steps.
  tool_step_ = jerk_.push(u);
  tool_mm_ = jerk_.at_rest() ? pos_mm_ : std::min(tool_mm_ + tool_step_, pos_mm_);
}

}  // namespace cncore::motion
