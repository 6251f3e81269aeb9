"""The ``routed`` strategy's planning: viewpoints, then a global tour over them.

Per decision (:class:`Router`, driven by :class:`~explore_seg.core.explorer.Explorer`):

0. The explorer splits every frontier group longer than ``frontier_split_m`` along its
   main axis into parts (:func:`~explore_seg.core.frontiers.split_frontiers`, FUEL's
   cluster split), once per map version.
1. :meth:`Router.viewpoints`: every frontier group gets a viewpoint
   (:mod:`.viewpoints`: the reachable pose from which a 360-degree sensor of
   ``sensor_range_m`` sees the most unknown area on the current map). The groups are
   returned with their cPoint replaced by the viewpoint, so the goal manager sends, keeps,
   judges and blacklists viewpoints exactly as it does cPoints.
2. :meth:`Router.tour_costs`: an open tour from the robot over the viewpoints of the
   selectable groups (:mod:`.tour`: greedy, 2-opt, Or-opt) on path lengths from the
   block graph the core already builds (one multi-source sweep for all pairs). DuDe
   regions are the routing structure: an edge between viewpoints of two different regions
   (or from the robot's region into another) costs ``region_switch_m`` (1 m) more, so a tour
   finishes a region before it leaves, unless what is left there is a detour of more than
   that. The cost of each group is the length of the tour when its viewpoint is visited
   next (the tour's first: the tour's length; the current goal's group: the best tour that
   starts with it; any other: the tour with it moved to the front), in metres. The goal
   manager's rule then becomes the tour hysteresis: the goal changes only when a tour
   shorter by ``hysteresis_margin`` of the current goal's tour exists (or the goal's
   frontier is gone), so goals do not flip on small map changes. A group whose viewpoint
   sees less than ``min_gain_m2`` of unknown area is left out (exploration ends rather
   than chasing frontier specks that reveal nothing). A viewpoint that sees less than
   ``leftover_gain_m2`` (2 m^2) is a leftover: it is left out of the tour while any
   viewpoint that sees more remains, and toured once only leftovers are left (small
   corners often vanish as the robot passes them; they no longer bend the tour); a group
   of ``leftover_max_length_m`` (3 m) of frontier cells or more is never one (the ragged
   end of max-range beams at the map's edge, whose view the edge cuts short).

Measured (lock step, seeds 0-2 of shared/house, shared/house_cluttered_plus, eb/corridor,
eb/loop, eb/room_2; paired with the baselines' rows of bench/results/runs.csv, median of
per-seed T95 ratios where both reached 95 %; ``bench/run_bench.py --runs 3 --jobs 1
--strategies routed --worlds ...`` runs the same, deterministic, runs). With
``viewpoint_radius_m`` = 0.75 m: ``routed`` / ``explore_lite`` 0.67 on shared/house,
0.77 on house_cluttered_plus (1 pair), 0.99 on eb/corridor, 1.02 on eb/loop, 1.12 on
eb/room_2 (all 13 pairs: 1.00); / ``nearest`` 0.47 (1 pair), 0.91 (1 pair), 0.89, 1.02,
1.09 (11 pairs: 0.92); 15 of 15 runs reached 99 %; path / coverage tour 1.02-1.24
(median per world). With 1.5 m the ratios to ``explore_lite`` were 0.68, 0.78, 1.09,
1.02, 1.24: viewpoints far from their frontier ended in more "goal reached but its
frontier remains" blacklistings and longer paths. It is faster in the furnished houses
and still slower than ``explore_lite`` on eb/room_2. Decision time (frontier detection +
viewpoints + tour + goal, median of 5 decisions on snapshots of a ``paper`` run on the
generated house at 60, 200 and 400 s, load average 3.8): 27-34 ms of CPU (``paper``:
6-7 ms), about three quarters of it viewpoints and tour; no p95 over whole runs on a
quiet machine yet.

Where the time went (issue #20, measured with ``bench/trace_decisions.py`` and lock-step
runs with the benchmark's settings, paired per seed with the ``explore_lite`` and
``nearest`` rows of bench/results/runs.csv):

- **Arrivals.** A viewpoint is a place the robot actually reaches, where a frontier cPoint
  recedes while the robot drives to it: routed ended 16 goals by arrival on eb/room_with_corner
  seed 0 (``explore_lite`` 4) and 6 on eb/room_2 seed 100 (``explore_lite`` and ``nearest``
  0), and stood still 30 s (23) and 8 s (1, 4). Each arrival costs the navigator's final
  turn and a decision period waiting for a newer map. ``handover_m`` = 1 m judges the goal
  while the robot still drives (:class:`~.goals.GoalManager`). Seeds 0-2 of eb/corner,
  eb/corridor, eb/room, eb/room_2 (12 pairs, handover 1 m vs 0): median T95 /
  ``explore_lite`` 1.096 -> 1.082, / ``nearest`` 1.051 -> 0.934, mean / ``explore_lite``
  1.199 -> 1.144; per pair (handover / none) median 0.995, mean 0.972, from 0.67 and 0.76
  (eb/corner seeds 0, 1: 387, 408 s -> 260, 312 s; ``explore_lite`` 274, 264) to 1.25 and
  1.26 (eb/room seed 2 209 -> 261 s, eb/room_2 seed 2 299 -> 376 s): a goal judged 1 m
  early whose frontier is still there is blacklisted, and some of those would have been
  cleared on arrival. Not a clear win; it stays on because the mean gains.
- **Goal switches are not the cost.** The tour hysteresis holds: 1 switch per run on
  eb/room_2 seed 100 and eb/room_with_corner seed 0 (``explore_lite`` 7 and 11,
  ``nearest`` 13).
- **Views that reveal little still bind the tour.** Without the handover, eb/corner seed 0
  sat at 93-94 % from 240 to 400 s: the tour's first goal was a 0.77 m^2 view 8.9 m away
  (it lay on the tour's way to the rest), then a 18 m drive. Holding views under 5 m^2 out
  of the tour unless they cost at most 2 m of detour (tried, not kept) made it worse there
  (338, 407 s vs 260, 312 s with the handover alone; eb/room_2 seed 0 282 vs 284 s).
- **Region routing helps.** ``region_switch_m`` 0 instead of 2 (with the handover):
  eb/corner 406, 377 s vs 260, 312 s; eb/room_2 286, 287 s vs 284, 289 s. With the
  leftovers held back (seeds 0-4 of 18 worlds,
  ``bench/results/paired/region_switch_handover_routed_seeds0-4.md``): 0 m gives 0.992
  (44 wins / 27 losses), faster in the Explore-Bench rooms (eb/corridor_asym 0.87,
  eb/room_3 0.91, eb/room_2 0.92), slower in the houses and the maze (generated house
  1.06, shared/maze 1.08) and one run stopped "done" at 95.2 %; 1 m gives 1.000 (31 / 21),
  all complete (0.973 / ``explore_lite``, 0.907 / ``nearest``, against 0.990 and 0.936
  with 2 m). Over seeds 0-14 (270 pairs, 1 m against 2 m,
  ``bench/results/paired/region_switch_1m_routed_seeds0-14.md``): all complete, 0
  contacts, per-seed T95 ratio median 1.000, geometric mean 0.988, 90 faster / 59 slower
  (eb/corner 12 / 0, eb/room 10 / 1, eb/room_1 9 / 1, eb/room_2 9 / 3, shared/house 9 / 3;
  shared/maze 4 / 10, eb/room_with_corner 5 / 8); time to 99 % 0.980 (geometric mean);
  the generated maze, seeds 0-2: 1.16, 1.04, 0.83 (``maze_routed_seeds0-2.md``): the
  larger region term pays in mazes, the smaller one in small rooms. 1 m is the default
  since. ``handover_m`` 0: 1.021 (7 / 31 over 9 worlds).
  ``gain_weight_m_per_m2`` 0.3 instead of 0.1: eb/corner seed 0 424 s vs 260 s. Again
  with today's code, 0.3 and 1.0 against 0.1 over seeds 0-2 of 9 worlds (the room worlds
  and those with headroom over the 95 % tour, below;
  ``bench/results/paired/gain_weight_routed_seeds0-2.md``): median per-seed T95 ratio
  1.025 (10 wins / 17 losses) and 1.116 (11 / 16); bigger views first helps in some
  worlds (0.3: eb/room_with_corner 0.76; 1.0: eb/room_3 0.92, shared/house 0.93) and
  costs more in others (eb/corner 1.42 and 1.23, eb/loop_with_corridor 1.03 and 1.42).
- **Turning back is not what loses the room worlds.** eb/room seed 1 (T95 257 s,
  ``explore_lite`` 196 s; per-decision log of goals and tour costs): at 20 s the current
  goal's frontier vanished and the next goal was chosen between two tours 0.02 m apart,
  one ahead of the robot, one behind; it took the one behind and drove back 5 m. FUEL
  adds a motion-consistency cost to the first leg for this. Tried (not kept): the first
  leg costing 1 m more per radian between the robot's heading and the straight line to
  the viewpoint, 10 worlds (the six where ``routed`` is > 5 % slower than the best
  baseline, eb/corner, eb/corridor_sym, house, shared/house), seeds 0-4, 16 pairs before
  I stopped it: median T95 ratio to today's ``routed`` 1.004, 5 wins / 11 losses
  (eb/corner 1.21, eb/room_3 1.18, eb/loop_with_corridor 1.10; shared/house 0.93). That
  seed itself went the other way and took 265 s. In these worlds time is path: on
  eb/room_1 seed 0 the mean speed to 95 % was 0.253 / 0.256 / 0.252 m/s (``routed`` /
  ``explore_lite`` / ``nearest``; top speed 0.26 m/s, sampled once per decision: above
  80 % of it in 98 % of the time), so only a shorter path helps; the same loop around
  the rooms was 59.8 m for ``routed`` and 54.2 m for ``explore_lite`` (a 1.7 m spur
  into the south-west room for a 34-cell corner that vanished before it was reached).
- **Neither the tail of the tour nor a lost goal frontier is it either** (tried, not
  kept; lock-step runs with the benchmark's settings, paired per seed with the ``routed``,
  ``explore_lite`` and ``nearest`` rows of the metric-lethal-disk run, ``out/margin``).
  (a) A group's cost as the first leg plus 0.5 x the rest of its tour (the map changes
  the rest before it is driven): eb/room seeds 0-2 took 283, 316, 263 s instead of 245,
  257, 218 s; leaning toward the nearest viewpoint loses. (b) eb/room_1 seed 1 lost about
  20 s at 197-221 s when its goal's frontier receded more than ``frontier_match_radius_m``
  from the viewpoint: the goal counted as "gone", the hysteresis no longer held, and a
  near-tie behind the robot won. Following the receding frontier (the group with a cell
  within 1.5 m of the goal frontier's last cells took the goal's place in the
  hysteresis test): 16 pairs in eb/room, room_1, room_2, room_3, loop_with_corridor and
  corridor_asym, seeds 0-2, median ratio 1.009 against today's ``routed`` (6 wins / 8
  losses), 1.084 against ``explore_lite``; eb/room_1 0.94, eb/room_2 1.04. (c)
  Viewpoints nearer the robot (``viewpoint_gain_tolerance`` 0.3 instead of 0.1: any
  candidate seeing 70 % of the best view), the same 6 worlds x 3 seeds: 1.001 against
  today's ``routed`` (7 / 7), 1.077 against ``explore_lite``. (d) The tour over the
  viewpoints as today, but the goal sent (and judged) at the chosen group's cPoint, on
  the frontier as ``explore_lite``'s, where the cPoint has a path: 1.000 against today's
  ``routed`` (8 / 6), 1.066 against ``explore_lite``. None of (a)-(d) moves the room
  worlds' gap to ``explore_lite``.
- **What separates ``explore_lite`` from ``routed`` in the room worlds is the frontier
  split together with the choice, not the cost alone** (diagnostic, same runs and
  pairing as above; the experiment code was not kept). Inside ``routed``'s pipeline,
  ``explore_lite``'s cost (3 x path length to the cPoint - frontier length) with the goal
  at the cPoint: 1.142 against ``explore_lite`` (16 pairs of the 6 worlds; eb/room
  1.27). The same with ``frontier_split_m``, ``handover_m`` and ``min_gain_m2`` all 0:
  1.009 (eb/room, room_1, loop_with_corridor, seeds 0-2), with only
  ``frontier_split_m`` 0: 1.000 (9 pairs; eb/room 1.000, room_1 1.005,
  loop_with_corridor 1.011; the same 9 pairs with the 3 m split: 1.187). So 3 m parts
  cost a greedy chooser about 16 % of its time there. For
  ``routed`` itself the split is needed: ``frontier_split_m`` 0 gives 1.034 against
  today's ``routed`` (loop_with_corridor 1.21); ``handover_m`` 0 1.036; ``min_gain_m2`` 0
  changes nothing in these worlds. The parts as routing structure only, in its plainest
  form (each unsplit group takes its best part's tour cost; goal and judging at the
  group's cPoint) is worse: eb/room seeds 0-2 268, 270, 235 s. What a greedy chooser
  gains from whole groups, a tour over parts has not yet been given.
- **Small views bent the tour; now they wait** (``leftover_gain_m2``). eb/room seed 0
  (``bench/trace_decisions.py``, ``routed`` vs ``explore_lite``): both drove the same loop
  round the rooms, 63.1 vs 57.6 m; the difference was a spur at 120-128 s into the
  south-west room for two views of 1.64 and 0.78 m^2 that vanished as the robot came
  near. Dropping views under 2 m^2 altogether (``min_gain_m2`` 2, seeds 0-2 of 10 worlds,
  ``bench/results/paired/min_gain_2_routed_seeds0-2.md``) sped up eb/room, room_1 and
  shared/house but ended eb/room_with_corner "done" at 98.5-98.9 % in 2 of 3 runs.
  Holding them back only while a bigger view remains keeps them for the end. Seeds 0-4
  of the 18 lock-step worlds, paired per seed against ``leftover_gain_m2`` 0 (``paired.py
  --out out/s23_lo2 --strategies routed --seeds 0-4 --arm
  lo2:explorer.selection.leftover_gain_m2=2.0`` against the ``routed`` rows of
  ``bench/results/paired/navigation_fallback_seeds0-4.md``): 90/90 complete, 0 contacts;
  median per-seed T95 ratio 1.000 with 31 wins / 15 losses; eb/room 0.936, eb/room_1
  0.945, eb/room_with_corner 0.833, shared/house 0.897, shared/maze 0.938, eb/loop
  1.005 and house 1.004 the largest losses. 4 m^2 against 2 m^2: 1.000 (28 / 24), with
  eb/loop 1.436 (the loop's far side waited as a leftover while the robot went round);
  2 m^2 is the default (``bench/results/paired/routed_default_seeds0-4.md``).
- **...but the ragged edge of the map is not a small view** (``leftover_max_length_m``).
  :func:`~.viewpoints.view_gain` counts outside the map as blocking, and the map grows
  only as far as scans reached (in whole chunks), so a frontier at its edge, where
  max-range beams ended in the open, sees little however much lies beyond. eb/loop seed 1
  at 81 s: the loop's continuation ahead, a ragged group of 155 frontier cells (0.75 x
  2.85 m, one cell from the map's border) 5 m away, saw 1.81 m^2, waited as a leftover,
  and the robot turned round for a view 15 m back; eb/room_3 seed 10 at 99 s the same (a
  136-cell group at the edge saw 1.62 m^2; the robot drove 30 m back; T95 639 s,
  ``explore_lite`` 417 s). A group of 3 m of frontier cells or more (cells x cell size;
  the split parts of a clean frontier stay under it, a ragged edge does not) is never a
  leftover now. Seeds 0-14 of the 18 lock-step worlds paired with the ``routed`` rows
  before this rule (arm ``cur`` of
  ``bench/results/paired/leftover_max_length_routed_seeds0-19.md``; ``paired.py --out
  out/s25_ll3 / out/s25_ll3b --strategies routed --arm
  ll3:explorer.selection.leftover_max_length_m=3.0``, 270 pairs): 270/270 complete, 0
  contacts; 257 runs identical (no such group came up), 10 faster, 1 slower, 2 within 1 %:
  eb/loop seeds 1, 2, 8, 13 270-272 -> 187-188 s (seed 6 189 -> 187 s), eb/room_3 seeds 2,
  7, 8, 10, 11 582 -> 500, 497 -> 460, 631 -> 504, 639 -> 419, 657 -> 499 s; shared/maze
  seed 5 532 -> 563 s (+5.8 %). 5 m gave the same 90 runs on seeds 0-4. Seeds 15-19
  (``out/s25_ll3c``): 85 of 90 identical, eb/loop seed 18 268 -> 187 s, eb/room_3 seeds
  17, 18 541 -> 478, 428 -> 418 s, house_cluttered seed 17 494 -> 505 s (+2.2 %),
  eb/room_3 seed 15 the same T95. Over the 20 seeds
  (``bench/results/paired/leftover_max_length_routed_seeds0-19.md``) 342 of 360 runs
  identical, 13 faster and 2 slower by more than 1 %, 3 within 1 %; against the baselines
  eb/room_3 went from 1.11x to within 5 % of the best one's median. The generated maze
  seeds 0-1 and the office floor seed 1: identical but maze seed 1 (3218 -> 3224 s);
  office seed 0 2961 s (``leftover_max_length_maze_office.md``). 3 m is the default.
  Tried, not kept: (a) counting outside the map as unknown in the ray cast (the padding
  and :class:`~.viewpoints.GainCache`'s grown-map fill): eb/room_3 seed 10 534 s, but
  seeds 0-4 of the 18 worlds (``out/s25_edge``, 90 pairs) 1.018 median per-seed T95 ratio,
  28 faster / 46 slower, geometric mean 1.011 (T99 0.992; eb/room 1.049, room_1 1.069,
  room_2 1.053, shared/house 1.126): every edge view then outbids the nearby views the
  tour finishes first; (b) exempting every group within 0.25 m of the map's border
  (``out/s25_le``, stopped after 18 runs: 5 changed, eb/room seed 0 212 -> 244 s,
  room_1 216 -> 236 s, eb/room_with_corner 413 -> 404 s).
- **The tour's tail pulls its head back to known routes, and routing through unknown
  space does not fix it** (tried, not kept). eb/loop_with_corridor seed 7 (T95 222 s,
  ``explore_lite`` 180 s; per-decision dump of every group's viewpoint, gain, tour cost
  and order): at 121 s, in the loop's south-west corner room, the tour visited the views
  toward the south corridor first and the corner last, because the tour then ends with
  the long leg to a view on the loop's east side, and that leg, through known space, goes
  back north round the loop; so the corner was passed, and at 229 s the robot drove 16 m
  back for it (28 m^2). A real robot closes the loop through the south. Tour lengths
  between viewpoints as the shorter of the known path and ``f`` x the path through
  free-or-unknown space (the graph of :meth:`~.distances.PathGraphs.fallback`; code
  489a459 on the local branch ``exp_opt``), 18 worlds x seeds 0-2 against today's rows
  (``bench/results/paired/tour_unknown_routed_seeds0-2.md``): ``f`` 1 median per-seed T95
  ratio 1.000, 10 faster / 24 slower, geometric mean 1.040 (eb/loop_with_corridor seed 3
  272 -> 201 s, but eb/corner 1.23, shared/maze 1.11, shared/house 1.10: unseen walls make
  most shortcuts through unknown space wrong), decision core p95 40 ms against 11 ms (the
  graph is built every decision); ``f`` 1.5 (30 runs) 1.000, 7 / 9, geometric mean 1.017.
  Nor does a local tour (TARE's horizon): while a viewpoint lies within 12 m of path, the
  tour left out those beyond (code 7c9deee, ``exp_opt``; ``out/s26_hz12``, stopped after
  33 of the 54 runs): median 1.000, 4 faster / 16 slower, geometric mean 1.049 (eb/corner
  seeds 0, 1 273 -> 351 and 265 -> 406 s, eb/loop_with_corridor seed 1 197 -> 299 s): the
  far views' legs are also what keeps the tour from leaving a region half seen.
- **A view into a corridor promises what its unseen walls hide** (tried, not kept).
  eb/room_2 seed 8 (T95 298 s; ``explore_lite`` 251, ``nearest`` 236; ``trace_decisions.py
  --groups 120:180``): from 132 to 154 s the robot followed the viewpoint of a dead-end
  corridor east as it receded (x 4.4 -> 9.2 m, goal frontier gone at every step), its view
  rated 30, 33, 27, 21, 10 m^2 while coverage rose 46.1 -> 48.9 %, about 8 m^2 in all: the
  ray cast lets rays through the corridor's walls while they are unknown and counts the
  rooms behind them; then it turned back. Each ray sample counted ``exp(-d / 2 m)``, ``d``
  the ray's length through unknown space before it (code d50877c, ``exp_opt``;
  ``out/s26_dc2``, 18 worlds x seeds 0-2, stopped after 23 runs): median per-seed T95
  ratio 1.005, 9 faster / 11 slower, geometric mean 1.009; faster in the rooms and houses
  (eb/room_3 561 -> 456 s, generated house 539 -> 483 s, eb/room_2 seed 8 298 -> 264 s),
  slower in corridors and the maze (eb/corridor 194 -> 238 and 199 -> 243 s, shared/maze
  540 -> 606 s). The leftover and minimum-gain thresholds were left at 2 and 0.25 m^2,
  which the decay makes stricter; a decay tuned with them is untried. A longer decay,
  4 m (``out/s27_dc4``, the 18 worlds x seeds 0-1, 36 runs, all complete, 0 contacts):
  median per-seed T95 ratio 0.998, 15 faster / 12 slower, geometric mean 0.996 (T99
  0.983); eb/corridor back to 195 / 197 s, eb/room_2 seed 0 251 s, but eb/room_3 seed
  0 538 s and eb/corridor_sym seed 1 184 -> 204 s: within what single runs swing (found
  uncommitted in the work tree; its runs are not kept and were not reproduced).
- **A dead-end pocket first is what loses eb/room_2, and a rate rule does not fix it**
  (tried, not kept; the experiment code was not kept). eb/room_2 seed 0
  (``bench/trace_decisions.py``, T95 269 s against ``explore_lite``'s 246 s): both drive
  the loop round the rooms, in opposite directions; at 34-57 s ``routed`` toured the
  2.5 m wide pocket in the north-west (views of 8-22 m^2, correctly estimated: coverage
  went from 28 to 32.4 %) and came back, while ``explore_lite`` went down the middle
  first (36 % at 50 s, 50 % at 75 s) and left the pocket for the end (its 250-275 s,
  after 95 %). A tour over today's views visits the pocket where it is cheapest to visit,
  which is first; the time to 95 % rewards the big openings first. Holding back views whose
  gain per metre of detour (the gain over what the tour saves without it) is below 0.5x
  the tour's own gain per metre, as leftovers, over seeds 0-2 of eb/room, room_1, room_2,
  room_3, loop_with_corridor, corridor_asym, room_with_corner, corner, house and
  shared/house (30 pairs against today's ``routed``): median per-seed T95 ratio 1.049,
  12 wins / 17 losses (eb/room 1.18, room_2 1.12, shared/house 1.17; room_with_corner
  0.90, corridor_asym 0.95), all complete. Single runs of these worlds swing by 10-20 %
  with any change of an early choice (the loop's direction), so 3 seeds judge only large
  effects.
  The principled form of "big openings first", a tour that minimises its length plus
  the gain-weighted mean distance at which each view is reached (the weighted latency of
  scheduling: 2-opt and node relocations on that objective after the shortest tour;
  weight 1), did no better on the same 30 pairs: 1.005 (14 wins / 13 losses), eb/room_3
  0.94, room_with_corner 0.94, room 0.97, but eb/corner 1.24 (3 of 3 slower) and
  loop_with_corridor 1.03. Both trade the houses' and corners' tour order for the rooms'
  first minutes.
- **Where any strategy can still gain: the 95 % tour.** The full-knowledge coverage
  tour cut where 95 % is in view (``bench/tasks.py`` ``tour_task``: ``tour95_m`` in
  ``tours.csv``; a heuristic, not a proven bound) is the path a robot that knew the map
  would drive to the time-to-95 % mark; driven at the stand-in's top speed (0.26 m/s,
  turns free) it gives a floor of T95. Medians of seeds 0-4 with the metric lethal disk
  (``bench/results/paired/six_strategies_metric_lethal_seeds0-4.md``) over that floor,
  ``explore_lite`` / ``nearest`` / ``routed``: eb/room 1.01 / 1.30 / 1.20, eb/room_1 1.08 /
  1.28 / 1.25, eb/loop 1.02 / 1.02 / 1.02, eb/loop_with_corridor 1.02 / 1.05 / 1.10,
  eb/corridor_asym 1.05 / 0.93 / 1.05 (tours 50.5, 49.0, 47.75, 46.75, 23.25 m). There the
  best baseline already drives about the informed tour, and a T95 0.90x of it would have
  to beat a robot that knows the map: in those worlds the target can only be parity. The
  headroom is elsewhere: eb/room_with_corner 2.03 / 2.11 / 1.74, shared/house 1.83 / 2.06
  / 1.52, house 1.71 / 1.59 / 1.18, eb/room_3 1.45 / 1.48 / 1.55, eb/corner 1.35 / 1.44 /
  1.31, eb/corridor 1.29 / 1.67 / 1.25. The 20-seed benchmark (older navigation) says the
  same by path: ``explore_lite``'s path to 95 % over the 95 % tour is 1.04 +- 0.07 on
  eb/room, 1.08 +- 0.09 on eb/room_1, 1.02 on eb/loop and eb/loop_with_corridor and 1.01
  on eb/corridor_asym (mean +- std, BENCHMARKS.md "path 95 / tour 95"; medians 1.00,
  1.03, 1.02, 1.02, 1.01).
- **The furnished houses' lead is the object costmap's.** ``routed`` runs with the object
  costmap, ``explore_lite`` and ``nearest`` without; ``paper`` / ``paper_noobj`` (same
  strategy, 20 seeds) has a median T95 ratio of 0.70 on shared/house, 0.84 on house, 0.95
  on house_cluttered and 1.00 in all 12 eb worlds (no objects there), so the 0.67 / 0.77
  above are not the routing's alone; the eb worlds compare the routing.
- **One viewpoint per long frontier jumps.** A corridor's unknown side is one connected
  frontier group (Alg. 1); its single viewpoint is where the best view of the whole
  group is, and that place jumps from one end to the other as the map grows. In
  eb/corridor_sym seed 0 (``bench/trace_decisions.py``-style decision logs) the goal of
  the one group of the corridor's south side went west, then east (32 s), west (35 s),
  east (42 s), west (34 s): T95 277 s against ``explore_lite``'s 185 s. Split into parts
  of at most 3 m (``frontier_split_m``), each part is a tour stop and the tour sweeps the
  corridor once: 186 s. Paired, seeds 0-2 of the 18 lock-step worlds, split 3 m vs none
  (``bench/results/paired/frontier_split_routed_seeds0-2.md``): median per-seed T95 ratio
  0.991, 26 wins / 20 losses; eb/corridor_sym 0.72, eb/loop 0.76, eb/loop_with_corridor
  0.88, eb/room 0.90, eb/corner 0.94; losses in eb/room_3 (1.18) and
  shared/house_cluttered (1.54: a reached part's neighbour "remained", was blacklisted and
  retried from across the house; with ``reached_unknown_fraction`` 0.5 seed 0 took 122 s
  instead of 187 s, unsplit 120 s). 2 m and 4.5 m on eb/room_2 and eb/corridor_sym seed 0:
  282 / 264 s and 186 / 186 s (3 m: 294 / 186 s). Longer parts over seeds 0-2 of 9
  worlds (``bench/results/paired/frontier_split_longer_routed_seeds0-2.md``, against 3 m):
  4.5 m 1.007 (8 wins / 12 losses), 6 m 1.041 (6 / 19); eb/room 1.000 and 1.014,
  eb/room_1 1.055 and 1.059, eb/loop_with_corridor 1.117 both, eb/corner 1.16 and 1.27.
- **Decision time** (CPU ms of the decision core per decision: frontier detection +
  viewpoints + tour + goal; process time, seed 0, load average 8-10 on 2 cores): p50 37,
  p95 52 on the generated house (whole run; ``explore_lite`` 13 / 26); p50 105, p95 201 on
  office_floor over its first 600 s (30 % coverage). Both are above the 50 / 150 ms targets;
  the lock step's decision_ms (with segmentation and the navigator's goal call) was p95 74
  and 239 ms.
- **Where the decision time went, and what is kept now.** A profile of office_floor seed 0
  (first 600 s, cProfile): the all-pairs path lengths between viewpoints (one Dijkstra
  sweep per viewpoint over the whole floor's path graph) 69 ms per decision, the view
  gains 24 ms plus 8 ms for the coarse map, the tour itself 6.5 ms. Both are now kept
  across decisions: gains per coarse cell (:class:`~.viewpoints.GainCache`, cast again
  only where the coarse map changed within the sensor range: the same values as a full
  cast, checked on every decision of two runs) and path lengths per viewpoint position
  (:class:`~.pair_paths.PairPaths`: sweeps from the new viewpoints, 4 of 65 per decision
  there, and the ``tour_refresh_rows`` oldest). Whole office_floor run, seed 0, CPU of the
  lock step: 1457 -> 724 s; selection p50 / p95 441 / 899 -> 68 / 135 ms, frontier
  detection p95 57 ms, lock-step decision p95 1116 -> 235 ms (runs of
  ``bench/paired.py --worlds office_floor --strategies routed --seeds 0``, the old one on
  a more loaded machine); T95 3196 -> 3495 s (kept lengths change the trajectory).
- **Decision core on a quiet machine** (the lock step's ``core`` timing: frontier
  detection + viewpoints + tour + goal of each decision, wall time; segmentation is a node
  of its own and not in it; one run alone on the 2 cores, seed 0, whole run, code 308b78b
  with the metric lethal disk): office_floor p50 / p95 / max 73.8 / 115.8 / 595 ms over
  4279 decisions (detection p95 19.4, selection p95 97.8), 77.5 / 119.5 / 576 ms with the
  code that keeps the robot's sweep (:class:`~explore_seg.core.block_graph.BlockGraph`;
  same trajectory; the difference is within run-to-run spread); the generated house 12.6
  / 19.8 / 718 ms over 575 decisions (the maximum is the first decision). Both under the
  issue's 150 / 50 ms. The earlier 235-269 ms figures were the lock step's ``decision`` (with
  segmentation) on a machine running other benchmark processes. Tried, not kept: the
  path sweeps from viewpoints on 2 threads: SciPy's Dijkstra holds the GIL (16 sweeps
  of a 35,470-node office graph: 79-103 ms on one thread, 85-118 ms on two), and the
  office run's core p95 was 126.2 ms with them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Sequence

import numpy as np
import numpy.typing as npt

from explore_seg.core.frontiers import Frontier, FrontierParams
from explore_seg.core.grid import GridMap, metres_to_cells
from explore_seg.core.selection.distances import PathGraphs
from explore_seg.core.selection.pair_paths import PairPaths
from explore_seg.core.selection.params import SelectionParams
from explore_seg.core.selection.regions import frontier_regions, region_at
from explore_seg.core.selection.tour import front_costs, solve_tour
from explore_seg.core.selection.viewpoints import GainCache, candidate_cells, pick_viewpoint


@dataclass(frozen=True)
class TourPlan:
    """The tour of one decision (for markers, traces and tests).

    Attributes
    ----------
    tour_cost_m : ndarray of float64, shape (N,)
        Per group: length of the tour when its viewpoint is visited next, minus
        ``gain_weight_m_per_m2`` times its gain (inf: not in the tour: unreachable,
        excluded, no passable viewpoint or a gain below ``min_gain_m2``).
    order : ndarray of int64
        Group indices in tour order.
    length_m : float
        Length of the best tour.
    regions : ndarray of int64, shape (N,)
        Region of each viewpoint (zeros without labels).
    robot_region : int
    gain_m2 : ndarray of float64, shape (N,)
        Unknown area seen from each viewpoint (zeros where none was computed).
    swept : int
        Viewpoints whose path lengths to the others were swept in this decision (the rest
        were kept: :class:`~.pair_paths.PairPaths`).
    """

    tour_cost_m: npt.NDArray[np.float64] = field(repr=False)
    order: npt.NDArray[np.int64]
    length_m: float
    regions: npt.NDArray[np.int64] = field(repr=False)
    robot_region: int
    gain_m2: npt.NDArray[np.float64] = field(repr=False, default_factory=lambda: np.zeros(0))
    swept: int = 0


class Router:
    """Viewpoints and tours of the ``routed`` strategy (see the module docstring).

    Parameters
    ----------
    frontier_params : FrontierParams
        ``occupied_threshold`` for the ray casting.
    params : SelectionParams
        The ``routed`` fields (sensor range, rays, viewpoint radius and step, region
        penalty) and ``region_search_radius_m``, ``unknown_path_factor``.
    """

    def __init__(self, frontier_params: FrontierParams, params: SelectionParams) -> None:
        self._fp = frontier_params
        self._p = params
        self._gains_kept = GainCache(params.sensor_range_m, params.gain_rays,
                                     frontier_params.occupied_threshold)
        self._pairs = PairPaths(params.tour_refresh_rows)
        #: Gain (m^2) of each group's viewpoint in the last :meth:`viewpoints` call.
        self.gain_m2: npt.NDArray[np.float64] = np.zeros(0)
        #: Wall seconds of the last :meth:`viewpoints` and :meth:`tour_costs` calls.
        self.viewpoint_s = 0.0
        self.tour_s = 0.0

    def reset(self) -> None:
        """Forget the kept gains and path lengths (a new map)."""
        self._gains_kept.reset()
        self._pairs.reset()

    def viewpoints(self, grid: GridMap, frontiers: Sequence[Frontier],
                   graphs: PathGraphs, start_rc: tuple[int, int] | None,
                   passable: npt.NDArray[np.bool_]) -> list[Frontier]:
        """The groups with their cPoint moved to their viewpoint.

        Parameters
        ----------
        grid : GridMap
        frontiers : sequence of Frontier
        graphs : PathGraphs
            Path graphs of this map version (reachability and distances from the robot).
        start_rc : (int, int) or None
            The robot's passable start cell (None: distances unknown, cPoints kept).
        passable : ndarray of bool, shape (H, W)
            Passable cells (viewpoint candidates).

        Returns
        -------
        list of Frontier
            Same order and cells; ``point_rc``/``point_xy_m`` at the viewpoint,
            ``point_passable`` True where a reachable viewpoint was found (else the group
            is unchanged).
        """
        t0 = time.perf_counter()
        p = self._p
        res = grid.resolution_m
        n = len(frontiers)
        self.gain_m2 = np.zeros(n)
        if n == 0 or start_rc is None:
            self.viewpoint_s = time.perf_counter() - t0
            return list(frontiers)
        radius = metres_to_cells(p.viewpoint_radius_m, res)
        step = max(1, metres_to_cells(p.viewpoint_step_m, res))
        cands = [candidate_cells(f.cells, f.point_rc, passable, radius, step)
                 for f in frontiers]
        counts = np.asarray([len(c) for c in cands])
        allc = np.concatenate(cands)
        dist = graphs.graph.distances(start_rc, allc)
        gain = self._gains_kept.gains(grid, allc)
        out: list[Frontier] = []
        bounds = np.concatenate([[0], np.cumsum(counts)])
        for i, f in enumerate(frontiers):
            a, b = int(bounds[i]), int(bounds[i + 1])
            # The cPoint (first candidate) competes only when it is passable.
            d = dist[a:b].copy()
            if not f.point_passable:
                d[0] = np.inf
            k = pick_viewpoint(gain[a:b], d, p.viewpoint_gain_tolerance)
            if k is None:
                # No reachable candidate (reachable through unknown space at most): keep
                # the cPoint, rated by the best view near the group.
                self.gain_m2[i] = float(gain[a:b].max())
                out.append(f)
                continue
            self.gain_m2[i] = gain[a + k]
            r, c = int(allc[a + k, 0]), int(allc[a + k, 1])
            if (r, c) == tuple(f.point_rc) and f.point_passable:
                out.append(f)
                continue
            out.append(replace(f, point_rc=(r, c), point_xy_m=grid.cell_to_world(r, c),
                               point_passable=True))
        self.viewpoint_s = time.perf_counter() - t0
        return out

    def tour_costs(self, grid: GridMap, frontiers: Sequence[Frontier],
                   dist_m: npt.NDArray[np.float64], excluded: npt.NDArray[np.bool_] | None,
                   graphs: PathGraphs, robot_rc: tuple[int, int],
                   labels: npt.NDArray[np.integer] | None, goal_index: int | None
                   ) -> TourPlan:
        """Tour over the selectable viewpoints and each group's cost (module docstring).

        Parameters
        ----------
        grid : GridMap
        frontiers : sequence of Frontier
            Groups at their viewpoints (:meth:`viewpoints`).
        dist_m : ndarray of float64, shape (N,)
            Path length robot -> viewpoint (inf: unreachable).
        excluded : ndarray of bool, shape (N,) or None
            Blacklisted groups (left out of the tour).
        graphs : PathGraphs
        robot_rc : (int, int)
        labels : ndarray of int, shape (H, W), or None
            Region labels (None or ``use_regions`` False: no region penalty).
        goal_index : int or None
            The current goal's group (its tour is solved with it first).

        Returns
        -------
        TourPlan
        """
        t0 = time.perf_counter()
        p = self._p
        n = len(frontiers)
        cost_out = np.full(n, np.inf)
        use = labels if (p.use_regions and labels is not None) else None
        rad = metres_to_cells(p.region_search_radius_m, grid.resolution_m)
        regions = frontier_regions(frontiers, use, rad)
        robot_region = region_at(use, robot_rc, rad) if use is not None else 0
        sel = np.isfinite(np.asarray(dist_m, dtype=np.float64))
        sel &= np.asarray([f.point_passable for f in frontiers], dtype=bool)
        # The last viewpoints' gains, when they belong to these groups.
        have_gains = len(self.gain_m2) == n
        gains = self.gain_m2.copy() if have_gains else np.zeros(n)
        if have_gains:
            sel &= gains >= p.min_gain_m2
        if excluded is not None:
            sel &= ~np.asarray(excluded, dtype=bool)
        if have_gains:
            # Leftovers last: small views wait while a bigger one remains.
            big = gains >= p.leftover_gain_m2
            if p.leftover_max_length_m > 0:
                big |= np.asarray([f.length_m for f in frontiers]) >= p.leftover_max_length_m
            big &= sel
            if big.any():
                sel = big
        idx = np.flatnonzero(sel)
        if idx.size == 0:
            self.tour_s = time.perf_counter() - t0
            return TourPlan(cost_out, idx.astype(np.int64), 0.0, regions, robot_region, gains)
        pts = np.asarray([frontiers[i].point_rc for i in idx], dtype=np.int64)
        m = idx.size + 1
        cost = np.zeros((m, m))
        cost[0, 1:] = np.asarray(dist_m, dtype=np.float64)[idx]
        pair = self._pairs.matrix(graphs.graph, grid, pts)
        bad = ~np.isfinite(pair)
        if bad.any():
            # Reachable from the robot only through unknown space (fallback distances):
            # straight line times the unknown-space factor.
            xy = pts.astype(np.float64) * grid.resolution_m
            straight = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
            pair = np.where(bad, straight * p.unknown_path_factor, pair)
        cost[1:, 1:] = pair
        if p.region_switch_m > 0 and use is not None:
            reg = np.concatenate([[robot_region], regions[idx]])
            differ = (reg[:, None] > 0) & (reg[None, :] > 0) & (reg[:, None] != reg[None, :])
            cost += np.where(differ, p.region_switch_m, 0.0)
        cost[:, 0] = 0.0
        np.fill_diagonal(cost, 0.0)
        tour = solve_tour(cost)
        front = front_costs(cost, tour)
        best_len, order = tour.length_m, tour.order
        if goal_index is not None and sel[goal_index]:
            node = int(np.flatnonzero(idx == goal_index)[0]) + 1
            if node != int(tour.order[0]):
                own = solve_tour(cost, first=node)
                front[node] = min(front[node], own.length_m)
                if own.length_m < best_len:
                    best_len, order = own.length_m, own.order
        cost_out[idx] = front[1:] - p.gain_weight_m_per_m2 * gains[idx]
        self.tour_s = time.perf_counter() - t0
        return TourPlan(cost_out, idx[order - 1].astype(np.int64), float(best_len), regions,
                        robot_region, gains, self._pairs.swept)


__all__ = ["Router", "TourPlan"]
