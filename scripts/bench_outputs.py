#!/usr/bin/env python3
"""Benchmark: the whole ``workspace`` command and its kernels against per-pose scipy LP.

For IPAnema 3 on a fine grid and for planar2, all in one run on this machine:

1. the baseline: per-pose scipy ``linprog`` (HiGHS) feasibility of a fixed
   random sample of the grid's poses, in this process, scaled to the whole
   grid (the LP answers feasibility only: no tensions, no margin, no file);
   timed before and after each round of 2 and 3, and each ratio taken within
   its round, because this machine's speed drifts between minutes;
2. the kernels in this process: ``workspaces.run`` without maps or rows, on
   its first call (numba's on-disk cache loaded) and warm;
3. the whole command, ``python -m cdpr_design workspace SPEC --step S --json``
   in a new process each time (start-up, spec, numba's start-up -- its
   ``load_s`` --, sweep, ``workspace.csv``, ``workspace.png``,
   ``tension_map.png``, ``summary.json``, exit), with ``--format csv`` and
   ``--format parquet``, warm (numba's cache and Python's bytecode written
   by a first run) and, unless ``--no-cold``, once with an empty numba cache
   (every kernel compiled); and the fixed costs under any command (a process
   that only starts Python, imports numpy, calls one small cached kernel,
   imports matplotlib);
4. the CSV writer alone on the IPAnema 3 rows: the previous one (printf per
   row, as ``io.tables.format_block`` was) against both paths of
   the vectorised numpy formatter (:func:`cdpr_design.io.csvtext.numpy_rows`) and the
   compiled one (:func:`cdpr_design.io.csvfast.numba_rows`) (warm, and its first call in the
   process with numba's cache warm).

Ratios are LP time for the grid / measured time, in wall-clock time and in CPU
time (user + system of all threads: less sensitive to other work on a shared
machine; the LP runs on one core, the kernels and the command on two; the
picture process, which the command does not wait for at exit, is not in the
command's CPU time).  ``--root`` runs the command
from another checkout (e.g. the previous version, for before/after; its
summary has no ``timings``, so its ``elapsed_s`` -- which then included the CSV
formatting -- stands in for ``sweep_s``).

    python3 scripts/bench_outputs.py [--step 0.14] [--sample 300] [--repeat 3] [--root DIR] [--no-cold]

Figures (2-core development machine shared with other virtual machines: its
speed drifts by up to 1.7x between minutes -- the LP took 1.6 to 3.0 ms a pose
over one afternoon, numba's start-up 1.0 to 1.75 s -- hence the rounds).  The
medians and ranges of three rounds, warm, load average below 1; "before" is
946fb56 (``--root``), "after" this version, run 5-10 minutes apart; the
kernels in this process are the current ones in both runs (the spread of
their ratio, 610-833x, is the machine's):

============================================  =========================  ===============================
IPAnema 3, 154,440 poses, static, csv         before (946fb56)           after (two runs)
============================================  =========================  ===============================
per-pose linprog over the rounds              1.73-2.62 ms               1.82-2.07 / 2.04-2.88 ms
whole command                                 3.76 s = 95x (85-97)       2.61 s = 108x / 2.86 s = 129x
  its load_s (numba's start-up)               (inside sweep_s)           0.63-0.78 s
  its sweep_s                                 1.32 s = 253x              0.55 s = 581x / 0.56 s = 728x
  best run: load / sweep / write / pictures   - / 1.03 / 0.74 / 0.84 s   0.63 / 0.34 / 0.45 / 0.51 s
kernels in-process, warm                      0.49 s = 833x              0.46 s = 610x / 0.54 s = 710x
============================================  =========================  ===============================

Larger IPAnema 3 grids (same version, LP timed around each run): 425,971 poses
(step 0.1 m) 3.8-4.2 s = 240-294x, ``sweep_s`` 522-870x; 1,192,605 poses (step
0.07 m) 7.0-7.9 s = 303-321x.  planar2 with its hanging tilt: 22,801 poses 1.93
s (23x) before, 1.67-1.73 s (29-32x) after; 564,001 poses 9.6 s (95x) before,
6.0-6.1 s (154-234x) after -- ``auto`` now gives grids over 130,000 poses to
the kernels, not to numpy.

Where the time went in that version (IPAnema 3, 154,440 poses, fastest run, wall): Python
start-up and the command's modules 0.3-0.45 s (numpy 0.1, typer with the
pydantic adapters it builds per option 0.1-0.2, the spec schema's pydantic
models 0.1); numba's start-up 0.63-0.78 s (``load_s``; a process that only
calls one small cached kernel takes 1.0-1.75 s from nothing, 0.3 s of it
scipy.linalg that numba imports at its first call -- and that imports
numpy.f2py); the sweep 0.34-0.56 s; then the table (0.2 s of CPU: the numba
CSV path) and the two pictures in the picture process (0.3 s of CPU each)
together 0.45-0.5 s; the exit 0.05 s.  The whole-process target (200x) needs
1.5 s at an LP of 2 ms a pose: the fixed costs of Python, numpy and numba
alone take about that, so at this grid size it is out of reach with a fresh
process per command; from about 400,000 poses it is met.  The kernel target
(1000x) is met in single rounds on an idle machine and missed in the medians.

What changed since 946fb56: numba's start-up timed apart (``load_s``, a one-pose
warm-up); the interpreter's exit skips its last garbage collections
(``gc.freeze()`` when the command is done: the exit went from 0.3-0.7 s to 0.05
s); the start-up's collections less frequent (0.15-0.2 s of CPU); the CSV
cells formatted by a numba kernel when numba is loaded; the pictures 0.52-0.62
of their CPU time (``scripts/bench_pictures.py``); ``auto``'s numpy limit
lowered to 130,000 poses.

The latest round (b78f933 -> this version), the same machine: a profile of every thread of the
command (``perf record`` at 2 kHz) found CPU spent on nothing.  numpy's OpenBLAS started a thread
that busy-waited 0.1 s for work that never came (a process that only imports numpy: 0.41 CPU-s,
0.27 with ``OPENBLAS_THREAD_TIMEOUT=4``, which the command line now sets unless the user did);
the garbage collector ran three collections in the command (31-35 ms) and two in the picture
worker's warm-up (40 ms) at a threshold of 50,000 (none at 200,000), and a full one (35-50 ms)
before the worker froze its objects (now frozen without it); ``fit_width`` measured every left
panel's y axis.  Then the main process's way to its sweep, which is what sets the command's
time now (below): rich imported only when something is printed for a person (40 ms less with
``--json``), the CSV writer's digit tables built without division (19 -> 8 ms).  IPAnema 3 in
16 interleaved pairs (medians): with the first four changes (7bda670), CPU of all its processes
4.02 -> 3.81 s and wall 2.19 -> 2.15 s; with all (in a faster half hour), 3.84 -> 3.57 s and
2.094 -> 2.010 s (-4 %).

The wall gains less than the CPU: the picture worker now ends its warm-up 0.83-0.86 s after the
start and waits about 0.1 s for the sweep (0.94-0.98 s to 1.25-1.31 s, timestamps without a
profiler), so CPU saved in it before the sweep shortens nothing.  What sets the time is the main
process's way to its sweep (Python and numpy 0.19 s, the command's modules and spec 0.3 s,
numba's start-up 0.4 s -- 43 ms of it ``numba.np.arrayobj``, imported to rebuild the environment
of ``np.empty`` in the cached sweep, and 20 ms ``numpy.ma``, which numba's ``typeof`` looks at --,
one after the other) and the two pictures after it (0.5 CPU-s each, beside the table's last
chunks: 0.6-0.7 s).  This script three times (medians, ranges of the rounds):

============================================  =============================  =========================
IPAnema 3, 154,440 poses, static              7bda670, two runs in one hour  this version
============================================  =============================  =========================
per-pose linprog over the rounds              2.96-3.20 / 3.10-3.20 ms       2.85-2.95 ms
kernels in-process, warm                      1666x / 1651x                  0.290 s = 1547x (1450-1589)
whole command, warm (csv)                     2.205 s = 217x (215-224) /     2.069 s = 217x (208-226)
                                              2.172 s = 227x (224-227)
  its sweep_s                                 1411x / 1487x                  0.324 s = 1359x (1306-1412)
whole command, warm (parquet)                 2.156 s = 221x (221-228) /     1.972 s = 225x (221-227)
                                              2.094 s = 236x (224-236)
planar2 564,001 poses, whole command          252x / 257x csv,               237x csv, 246x parquet
                                              253x / 263x parquet            (linprog 2.3-2.6 ms)
============================================  =============================  =========================

At the end of the round, this script with the cold run, then with ``--root`` at 946fb56 (the
version before the columnar writer, the timings and the picture process), 20 minutes apart:

============================================  ==========================  ==========================
                                              946fb56                     this version
============================================  ==========================  ==========================
IPAnema 3: per-pose linprog                   2.79-2.80 ms                2.88-3.12 ms
  whole command, cold numba cache (csv)       69.1 s = 5.4x               30.3 s = 16x (load_s 26.7 s)
  whole command, warm (csv)                   3.945 s = 109x (108-110)    2.044 s = 230x (218-231)
  its sweep_s                                 1.471 s = 294x              0.326 s = 1413x (1409-1477)
  whole command, warm (parquet)               -                           2.067 s = 227x (221-233)
planar2 22,801 poses, warm (csv)              2.089 s = 29x               1.762 s = 39x
planar2 564,001 poses, cold (csv)             12.6 s = 116x               16.1 s = 104x
planar2 564,001 poses, warm (csv / parquet)   12.5 s = 123x / -           6.42 s = 245x / 6.27 s = 260x
============================================  ==========================  ==========================

b78f933 in this script's run just before the first (linprog 3.21-3.28 ms): 233x (226-233).  The
ratio follows the hour's linprog more than a change of a few per cent (hence the interleaved
pairs): the round before measured b78f933 at 193x in an hour when linprog took 2.5-2.7 ms a
pose; 4 % less wall would make that about 200x.

The round before (38e9c27 -> b78f933), a fourth machine (per-pose linprog 2.4-3.5 ms,
drifting by the hour): the picture worker is a copy of the command (``os.fork`` once numpy
is imported; it skipped Python's start-up, its site and numpy: its CPU to the end of its
warm-up 1.03-1.15 -> 0.80-0.91 s), and a command line builds only its own command's options
(``cli.app.make_app``; the command's modules 0.33 -> 0.28 s in the fixed costs below).  The
command is CPU-bound on two cores: its processes use 3.7-4.5 CPU-s in 2.0-2.5 s (``perf stat``
task-clock), the picture worker's warm-up ending about when the sweep does, so no core
waits idle for long (figure layouts built in the worker while the sweep ran, 0.18 of a
spatial picture's 0.52 CPU-s, were tried and gained nothing).  IPAnema 3 in 12 interleaved
pairs: 2.185 -> 2.042 s wall (medians), 4.02 -> 3.74 CPU-s.  This script, back to back in one
hour:

============================================  ==========================  ==========================
IPAnema 3, 154,440 poses, static              38e9c27                     b78f933
============================================  ==========================  ==========================
per-pose linprog over the rounds              2.37-2.45 ms                2.47-2.69 ms
kernels in-process, warm                      0.284 s = 1306x (1291-1371) 0.276 s = 1406x (1393-1447)
whole command, warm (csv)                     2.169 s = 174x (168-174)    2.029 s = 193x (187-204)
  its sweep_s                                 0.325 s = 1163x             0.334 s = 1196x (1092-1243)
whole command, warm (parquet)                                             1.976 s = 195x (193-210)
fixed: python and the command's modules       0.331 s                     0.284 s
planar2 564,001 poses, whole command          204x csv                    207x csv, 212x parquet
============================================  ==========================  ==========================

The same script earlier that day, in an hour when linprog took 3.1-3.5 ms a pose: 38e9c27 207x
(206-208), b78f933 197x (186-205, load average 1.6): the ratio moves with the hour more
than with a change of 6 %, hence the interleaved pairs above.

The round before (from 82599a7), on the third machine: the cached kernels
load without numba's compiler set-up (``cdpr_design.numba_startup``: numba
refreshed its whole target context -- every implementation module it has --
before each cache load, 0.15-0.2 s of a command).  IPAnema 3's command in 10
interleaved pairs against 82599a7 (medians): 2.03 -> 1.72 s wall (fastest 1.75
-> 1.61 s), ``load_s`` 0.53 -> 0.32 s, ``total_s`` 1.43 -> 1.13 s; CPU of the
command and its picture process 3.3 -> 2.9 s.  This script, once each in the
same slow hour (per-pose linprog 1.83-2.50 ms; a process that imports numpy
and numba and calls one cached kernel: 0.82 s before, 0.67 s after):

============================================  ==========================  ==========================
IPAnema 3, 154,440 poses, static              82599a7                     this version
============================================  ==========================  ==========================
kernels in-process, warm                      0.307 s = 1235x (1078-1474) 0.265 s = 1347x (1096-1427)
whole command, warm (csv)                     2.63 s = 130x (125-147)     2.05 s = 159x (131-184)
  its sweep_s                                 0.348 s = 967x (960-1111)   0.294 s = 1131x (926-1337)
whole command, warm (parquet)                                             2.04 s = 153x (151-185)
fastest csv run: load / sweep / write / pics  0.69 / 0.34 / 0.63 / 0.73 s 0.33 / 0.31 / 0.44 / 0.53 s
============================================  ==========================  ==========================

Where the time goes now (IPAnema 3, a faster hour, the command 1.53-1.61 s
from the shell, timeline of the main process): Python, numpy, typer and the
command's modules 0.20 s; the options' pydantic adapters, the spec and its
schema 0.23 s; numba's import and the kernels' load 0.27 s (``load_s``); the
sweep 0.21 s; the table's last chunks 0.27 s and the pictures' last 0.17 s
(the two pictures, 0.57 s of CPU, drawn by the picture process and a fork of
it beside the table's writer); the exit 0.05 s.  The first 0.9 s keep both
cores busy (the picture process imports matplotlib meanwhile, 0.7 s).

planar2 564,001 poses, this version: 183x csv (166-199), 195x parquet (192-205).
``auto``'s numpy limit lowered to 70,000 poses (the crossover with the cheaper
start-up; ``workspaces/engine.py``).

The round before (bdf8ba0 -> 82599a7), the same machine: the picture process
back at the command's CPU priority (niced +10 it waited behind every other
process on a busy machine: planar4's command beside three busy processes
17.6 s, now 3.4 s; IPAnema 3's on an idle machine 1.60 -> 1.65 s, medians of
ten).  One run of this script at the end, median round and range of three,
per-pose linprog 1.60-1.64 ms that hour (faster than in the round below, so
the same command times give lower ratios): IPAnema 3 kernels warm 0.168 s =
1500x (1473-1508), whole command 1.665 s = 149x csv (147-153) and 1.590 s =
156x parquet (153-160), its sweep_s 1219x / 1190x; fastest csv run load 0.46
/ sweep 0.19 / write 0.41 / pictures 0.47 s; planar2 564,001 poses 199x csv,
202x parquet; fixed: python, numpy, numba, one kernel 0.69 s.

The round before (811e3e9 -> bdf8ba0), on a third machine, about twice as slow
as the second (per-pose LP 1.6-2.6 ms): numba's start-up without
``scipy.linalg`` (``kernels._jit._load_blas_check``: its BLAS check answered
by the one extension module it looks for), and the picture process importing
the figure modules while it waits.  A process that only imports numpy and
numba and calls one cached kernel: 1.09 -> 0.83 s; its first call 0.45-0.53 ->
0.17-0.23 s.  IPAnema 3's command in 10 interleaved pairs against 811e3e9
(medians): 1.89 -> 1.76 s wall, ``load_s`` 0.63 -> 0.45 s (an earlier run of 8
pairs: 2.09 -> 1.78 s).  This script, one run each (median round and range of
three; before at the start of the session, after at its end):

============================================  ==========================  ==========================
IPAnema 3, 154,440 poses, static              811e3e9                     bdf8ba0
============================================  ==========================  ==========================
per-pose linprog over the rounds              1.68-2.63 ms                1.81-2.02 ms
kernels in-process, first call                0.722 s                     0.526 s
kernels in-process, warm                      0.191 s = 1431x (1203-1511) 0.180 s = 1647x (1196-1763)
whole command, warm (csv)                     2.04 s = 142x (134-152)     1.85 s = 166x (151-174)
  its sweep_s                                 0.248 s = 1118x             0.252 s = 1238x (1052-1369)
whole command, warm (parquet)                 1.83 s = 150x (146-163)     1.85 s = 161x (149-182)
  fastest run: load / sweep / write / pics    0.56 / 0.21 / 0.24 / 0.46   0.44 / 0.22 / 0.22 / 0.53 s
whole command, cold numba cache (csv)         -                           20.7 s = 13x (load_s 18.2 s)
fixed: python, numpy, numba, one kernel       1.09 s                      0.83 s
planar2 564,001 poses, whole command          178x csv, 195x parquet      196x csv, 194x parquet
============================================  ==========================  ==========================

Where the whole command's time goes now (timestamps in the process, two
cores): start-up to the spec loaded 0.45-0.5 s (Python and site 0.1, numpy
0.08, typer and the command modules 0.15, pydantic and the spec schema
0.2); numba's start-up, ``load_s``, 0.45 s (measured apart in a fresh
process, 0.53-0.66 s: its import 0.22-0.35, its array functions 0.08, the
first call's registry refresh 0.2, the cached kernels 0.03); the
sweep 0.22 s; then the two pictures (0.3 s of CPU each, in two processes)
with the table's last chunks (about 0.25 s of CPU) in 0.45 s, which is what
the two cores can do; the exit 0.05 s.  The picture process imports
matplotlib (0.7-1.0 s of CPU) on the second core meanwhile and is ready
before the sweep ends.  200x allows 1.49 s at this LP: the fixed costs and
the pictures are past it at this grid size, the kernels far below.

The round before (703c4fd -> 811e3e9): every straight-cable loop over poses,
and the CSV row formatter, compiled without numba's reference counting
(``kernels._jit.njit_noref``; ``io.csvfast._NOREF``).  One core, in-process,
old against new on the same grid: IPAnema 3 2.66 -> 1.21 us a pose, IPAnema 2
2.12 -> 0.91, pointmass3 (m = n) 0.39 -> 0.135, CoGiRo with interference
checks 4.41 -> 2.01; the CSV formatter 58 -> 17 ns a cell.  The shipped
designs' workspace.csv byte-identical.  On a new machine, whose per-pose LP
is 1.7x faster than the previous one's (0.86-0.93 ms; the kernels were 1.08x
faster there).  One run each, idle machine, median round and range of three:

============================================  ==========================  ==========================
IPAnema 3, 154,440 poses, static              703c4fd                     this version
============================================  ==========================  ==========================
per-pose linprog over the rounds              0.86-0.87 ms                0.91-0.93 ms
kernels in-process, warm                      0.199 s = 669x (664-672)    0.099 s = 1415x (1314-1474)
whole command, warm (csv)                     1.17 s = 114x (108-122)     1.00 s = 144x (139-144)
  its sweep_s                                 0.254 s = 523x (517-542)    0.117 s = 1192x (824-1267)
whole command, warm (parquet)                 0.99 s = 135x (126-136)     0.93 s = 151x (147-154)
  its sweep_s                                 0.232 s = 573x (549-629)    0.138 s = 1015x (954-1163)
  fastest run: load / sweep / write / pics    0.28 / 0.25 / 0.27 / 0.29   0.32 / 0.12 / 0.15 / 0.24 s
CSV of the table (3.7 M cells), numba path    0.223 s                     0.065 s
fixed: python, numpy, numba, one kernel       0.53 s                      0.52-0.75 s
planar2 564,001 poses, whole command          2.61 s = 162x csv           2.77 s = 168x csv, 2.64 s = 174x parquet
============================================  ==========================  ==========================

The kernel target (1000x) is met in this process and by the command's
``sweep_s``.  The whole-command target (200x) allows 0.70 s at 0.9 ms a pose:
a process that only imports numpy and numba and calls one small cached kernel
took 0.52-0.75 s in these runs, so at this grid size a fresh process per
command cannot reach it on this machine.  Larger IPAnema 3 grids (one round
each, LP 0.89-0.92 ms): 425,971 poses (step 0.1 m) 1.35 s = 291x csv, 1.22 s =
321x parquet, ``sweep_s`` 1159x / 1062x; 1,192,605 poses (step 0.07 m) 2.74 s =
390x csv, 2.16 s = 494x parquet, ``sweep_s`` 736x / 918x (the table's writer
shares the two cores with the sweep; the kernels alone 1478x).  planar2 is
unchanged (its hanging tilt keeps reference counting: its polynomial roots
allocate).

The round before (c518a27 -> 703c4fd): the pose function's margin and QP methods
called directly, with the function inlined into the sweeps' loops, and one grid
kernel per redundancy m - n chosen in Python (``kernels.sweep.grid_block``):
3.56 -> 2.62 us a pose of IPAnema 3 on one core; the picture process at a
lower CPU priority (``nice`` +10, taken back since: on a busy machine it left the
pictures waiting behind every other process).  One run, idle machine (load
average 0.7 at the start; median round and range of three):

============================================  ================================
IPAnema 3, 154,440 poses, static              this version
============================================  ================================
per-pose linprog over the rounds              1.54 ms
whole command, warm (csv)                     1.62 s = 147x (144-150)
  its sweep_s                                 0.249 s = 955x (914-985)
  fastest run: load / sweep / write / pics    0.48 / 0.24 / 0.22 / 0.41 s
whole command, warm (parquet)                 1.56 s = 153x (149-153)
  its sweep_s                                 0.254 s = 934x (917-958)
kernels in-process, warm                      0.216 s = 1102x (1097-1106), 717,000 poses/s
whole command, cold numba cache (csv)         32.1 s = 7.5x (load_s 30.1 s; 23.6 s in a run an hour earlier)
planar2 564,001 poses, whole command warm     3.97 s = 201x csv, 3.87 s = 206x parquet
============================================  ================================

The kernels pass 1000x in this process; the command's ``sweep_s`` is 0.03 s
longer (its first sweep in a fresh process, next to the picture process's
start) and stays just under.

The round before (d76ba24 -> c518a27): Parquet pages dictionary-encoded only
for non-float columns (``io.columns._parquet_writer``): writing IPAnema 3's
workspace table (154,440 x 24) took 0.26 s and made 22.1 MB with dictionaries
on every column, 0.06 s and 19.0 MB after; the command's ``write_s`` with
``--format parquet`` went from 0.62 s (previous run of this script) to
0.12-0.21 s, and that command is now the faster of the two formats.  One run,
an idle machine (load average 0.5 at the start; median round and range of
three):

============================================  ================================
IPAnema 3, 154,440 poses, static              c518a27
============================================  ================================
per-pose linprog over the rounds              1.57-1.69 ms
whole command, warm (csv)                     1.87 s = 134x (131-134)
  its sweep_s                                 0.33 s = 763x (719-780)
  fastest run: load / sweep / write / pics    0.52 / 0.32 / 0.40 / 0.46 s
whole command, warm (parquet)                 1.83 s = 139x (134-142)
  fastest run: load / sweep / write / pics    0.53 / 0.34 / 0.16 / 0.37 s
kernels in-process, warm                      0.28 s = 864x (861-898), 544,000 poses/s
whole command, cold numba cache (csv)         37.3 s = 6.5x (load_s 35.0 s)
planar2 564,001 poses, whole command warm     4.49 s = 199x csv, 4.21 s = 208x parquet
============================================  ================================

The LP ran faster than in earlier runs (1.6 ms a pose against 1.7-2.6), which
lowers every ratio: at 1.6 ms the 200x budget of the whole command is 1.24 s,
and a process that only starts Python, imports numpy and numba and calls one
small cached kernel takes 0.79 s of it.  Tried and dropped this round: skipping
numba's registry refresh when a kernel comes from the cache (0.4 s of
``load_s``; the process segfaults -- the refresh also registers the helper
symbols the compiled code links to), and testing each HSM facet against the
running minimum before its square root (hsm 1.41 -> 1.31 us a pose, 2.5 % of
the pose: below the noise, not worth the code).

The round before (1576a64 -> d76ba24): the minimum-norm tensions in closed form
for one or two redundant cables (``kernels.tension_qp.project_two``): 0.97-1.04
-> 0.64-0.76 us a pose of IPAnema 3 on one core, in interleaved runs over the
grid's 142,237 feasible poses, out of 3.7-4.1 us for the whole pose.  In this
script the gain is below the machine's noise; three runs (load average 0.8,
0.9 and 1.25 at the start; median round and range of three):

============================================  ==================  ==================  ==================
IPAnema 3, 154,440 poses, static              run 1               run 2               run 3
============================================  ==================  ==================  ==================
per-pose linprog over the rounds              1.78-2.18 ms        1.94-2.15 ms        1.68-1.74 ms
whole command, warm (csv)                     2.66 s = 105x       2.65 s = 119x       2.36 s = 114x
  its sweep_s                                 0.41 s = 689x       0.47 s = 704x       0.41 s = 658x
  fastest run: load / sweep / write / pics    0.81/0.48/0.57/0.75 0.75/0.47/0.35/0.58 0.69/0.35/0.58/0.58
whole command, warm (parquet)                 2.58 s = 125x       3.06 s = 103x       2.40 s = 112x
kernels in-process, warm                      0.47 s = 704x       0.39 s = 808x       0.32 s = 844x
  range over the rounds                       598-867x            722-933x            645-901x
whole command, cold numba cache (csv)         50.8 s (load 47.3)  -                   -
planar2 564,001 poses, whole command warm     5.7 s = 186x        6.5 s = 189x        4.7 s = 183x
============================================  ==================  ==================  ==================

In five interleaved pairs of the IPAnema 3 command, 1576a64 against this version,
``sweep_s`` was 0.34-0.44 s (median 0.356) before and 0.32-0.39 s (median 0.328)
after; planar2's 564,001 poses in three pairs 2.71-2.92 s before and 2.62-2.73 s
after (no change there: m = n).

The round before (54fea28 -> 1576a64): the parallel kernels run their blocks
of poses on a thread pool (``kernels/parallel.py``) instead of numba's
``prange``, and the sweeps call the square-case evaluation directly.  Cold
(an empty numba cache), the IPAnema 3 command took 77.2 s wall before (its
``load_s`` 72.7 s) and 53.7 s (``load_s`` 49.4 s) with the thread pool, the
two run side by side on the two cores; after the second change, alone on the
machine, 47.8 s (``load_s`` 43.9 s).  Warm, the same within the machine's
noise: in five interleaved pairs the whole command took 2.21-2.75 s before and
2.22-2.69 s after.  One run of this script on 1576a64 (load average
1.6 at the start; median round and range of three):

============================================  ================================
IPAnema 3, 154,440 poses, static              1576a64
============================================  ================================
per-pose linprog over the rounds              1.87-2.29 ms
whole command, warm (csv)                     2.75 s = 117x (115-119)
  its sweep_s                                 0.46 s = 654x (647-706)
  fastest run: load / sweep / write / pics    0.72 / 0.45 / 0.42 / 0.57 s
whole command, warm (parquet)                 3.09 s = 114x (92-121)
kernels in-process, warm                      0.41 s = 804x (655-881)
whole command, cold numba cache (csv)         47.8 s = 6.4x (load_s 43.9 s)
planar2 22,801 poses, whole command warm      1.31 s = 27x (numpy engine)
planar2 564,001 poses, whole command warm     5.3 s = 269x (206-300)
planar2 564,001 poses, cold                   10.8 s (load_s 5.9 s)
============================================  ================================

The previous round (e612e10 -> 946fb56, the closed-form margin of
``kernels.hsm_small``): kernel CPU per IPAnema 3 pose 5.8-6.1 us -> 3.7-3.9 us in
interleaved runs; cold (an empty numba cache, every kernel compiled) 36 s ->
57-65 s, measured under heavy load.

The CSV writer alone on the IPAnema 3 rows (3,706,560 cells, one core, load
below 1): previous writer 590-683 ns/cell, numpy ``csv_rows`` 119-136 ns/cell,
numba ``csv_rows`` 54-57 ns/cell warm (10-13x the previous writer, 2.1-2.5x
numpy), 53-72 ns/cell on its first call (the compiled code loaded from
numba's cache).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from cdpr_design import workspaces as ws  # noqa: E402
from cdpr_design.model import spec  # noqa: E402
from cdpr_design.statics import kinematics as kin  # noqa: E402
from cdpr_design.workspaces.grid import grid_positions  # noqa: E402


def lp_poses(design, grid, count, rng) -> list[list[float]]:
    """A random sample of ``count`` poses of the grid (the LP baseline's poses)."""
    idx = np.sort(rng.choice(grid.size, size=min(count, grid.size), replace=False))
    ori = list(design.workspace.orientation or [])
    return [list(grid_positions(grid, int(i), 1)[0]) + ori for i in idx]


def lp_seconds_per_pose(design, poses) -> tuple[float, float]:
    """Mean (wall, CPU) time [s] of one per-pose linprog feasibility check over ``poses``."""
    from scipy.optimize import linprog

    bounds = list(zip(design.tension_min, design.tension_max))
    t0, c0 = time.perf_counter(), time.process_time()
    for pose in poses:
        W = kin.structure_matrix(design, pose)
        w = kin.required_wrench(design, pose)
        linprog(np.zeros(design.m), A_eq=W, b_eq=w, bounds=bounds, method="highs")
    return (time.perf_counter() - t0) / len(poses), (time.process_time() - c0) / len(poses)


def _timed(fn, cpu: bool = False):
    t0, c0 = time.perf_counter(), time.process_time()
    fn()
    wall = time.perf_counter() - t0
    return (wall, time.process_time() - c0) if cpu else wall


def command(root: Path, spec_path: Path, step: float | None, fmt: str, out: str, cache: str | None):
    """Wall time [s] of one ``workspace`` process and its summary."""
    env = _env(root)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    args = [sys.executable, "-m", "cdpr_design", "workspace", str(spec_path), "--out", out, "--json", "--overwrite"]
    if step is not None:
        args += ["--step", str(step)]
    if fmt != "csv":
        args += ["--format", fmt]
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run(args, env=env, cwd=root, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode:
        raise SystemExit(f"{' '.join(args)} failed ({r.returncode}): {r.stderr[-500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return (wall, cpu), json.loads(r.stdout)


def _env(root: Path) -> dict:
    """The commands' environment: ``root`` first on the path, and Python's bytecode cache
    allowed (an installed package has its ``.pyc`` files; a machine set to
    ``PYTHONDONTWRITEBYTECODE`` would otherwise compile every module of the package from
    source in every run, 0.3-0.5 s)."""
    env = dict(os.environ, PYTHONPATH=str(root))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


FLOOR = {
    "python start-up": "pass",
    "python, numpy": "import numpy",
    "python, numpy, numba, a small cached kernel's first call": ("import numpy as np; from cdpr_design.kernels.linalg import det_small; "
                                                "det_small(np.eye(2), 2)"),
    "python, the command's modules (no numba)": "import cdpr_design.cli.app, cdpr_design.jobs.workspace",
    "python, matplotlib.pyplot (the picture process)": "import matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot",
}


def floor_times(root: Path, repeat: int) -> list[tuple[str, float]]:
    """Best wall time [s] of a fresh process doing only each of :data:`FLOOR`: the fixed
    costs under every command, whatever its grid."""
    out = []
    for what, code in FLOOR.items():
        args = [sys.executable, "-c", code]
        subprocess.run(args, env=_env(root), cwd=root, check=True)  # bytecode and numba cache written
        best = min(_timed(lambda: subprocess.run(args, env=_env(root), cwd=root, check=True))
                   for _ in range(repeat))
        out.append((what, best))
    return out


def sweep_s(summary: dict) -> float:
    return summary["timings"]["sweep_s"] if "timings" in summary else summary["elapsed_s"]


def previous_format_block(columns, int_cols) -> str:
    """The previous CSV writer of workspace rows: one printf per row, NaN cells removed by a regex."""
    ints = set(int_cols)
    fmt = ",".join("%d" if j in ints else "%.10g" for j in range(len(columns)))
    block = np.column_stack([np.asarray(c, dtype=float) for c in columns])
    text = "\n".join([fmt % row for row in map(tuple, block.tolist())]) + "\n"
    return re.sub(r"(?<![^,\n])-?(?:nan|inf)(?![^,\n])", "", text)


def _prime_csv_kernel() -> None:
    """numba's on-disk cache of the compiled CSV formatter filled, by another process."""
    code = "import numba, numpy; from cdpr_design.io.csvfast import numba_rows; numba_rows([numpy.ones(3)])"
    subprocess.run([sys.executable, "-c", code], env=dict(os.environ, PYTHONPATH=str(ROOT)), check=True)


def writer_times(design, grid, repeat: int) -> dict:
    """Seconds to format every row of the grid as CSV text, and the cell count (``cells``).

    ``previous``: printf per row; ``numpy``: :func:`cdpr_design.io.csvtext.numpy_rows`;
    ``numba_cold``: the first call of :func:`cdpr_design.io.csvfast.numba_rows` in this
    process (numba's cache warm: loaded, not compiled); ``numba``: warm (best of ``repeat``)."""
    from cdpr_design.io import csvfast
    from cdpr_design.io.csvtext import numpy_rows

    _prime_csv_kernel()
    chunks = []
    ws.run(design, grid=grid, keep_maps=False, on_chunk=chunks.append)

    def cols(c):
        return ([c.poses[:, j] for j in range(c.poses.shape[1])] + [c.feasible, c.margin]
                + [c.tensions[:, i] for i in range(c.tensions.shape[1])] + [c.lengths[:, i] for i in range(c.lengths.shape[1])])

    k = chunks[0].poses.shape[1]
    out = {"numba_cold": _timed(lambda: [csvfast.numba_rows(cols(c)) for c in chunks])}
    out["previous"] = min(_timed(lambda: [previous_format_block(cols(c), [k]) for c in chunks]) for _ in range(repeat))
    out["numpy"] = min(_timed(lambda: [numpy_rows(cols(c)) for c in chunks]) for _ in range(repeat))
    out["numba"] = min(_timed(lambda: [csvfast.numba_rows(cols(c)) for c in chunks]) for _ in range(repeat))
    out["cells"] = sum(len(cols(c)) * len(c.feasible) for c in chunks)
    return out


def print_writer_times(t: dict) -> None:
    cells = t["cells"]

    def ns(what):
        return f"{t[what]:.3f} s ({t[what] / cells * 1e9:.0f} ns/cell)"

    print(f"\nCSV of the IPAnema 3 rows ({cells:,} cells): previous writer {ns('previous')}, numpy csv_rows "
          f"{ns('numpy')}, numba csv_rows warm {ns('numba')}, cold (first call, cache warm) {ns('numba_cold')}: "
          f"numba {t['previous'] / t['numba']:.1f}x the previous writer, {t['numpy'] / t['numba']:.1f}x numpy; "
          f"numpy {t['previous'] / t['numpy']:.1f}x the previous writer")


def bench_design(name: str, step: float | None, args, rng) -> dict:
    """Rounds of (LP, kernels warm, whole commands, LP again) for one design; prints the table.

    The machine's speed drifts (the LP took 1.6-3.1 ms a pose between runs of one day on
    the shared machine), so every round times the LP around what it is compared with, and
    each ratio is taken within its round; the table gives the median round and the range.
    """
    path = ROOT / "designs" / f"{name}.yaml"
    d = spec.load(path)
    g = ws.make_grid(d, step)
    poses = lp_poses(d, g, args.sample, rng)
    root = Path(args.root).resolve() if args.root else ROOT
    fmts = ("csv", "parquet") if not args.root else ("csv",)
    label = f"{name} ({g.size:,} poses, step {step or d.workspace.grid.step[0]} m)"
    print(f"\n{label}: per-pose linprog over {len(poses)} poses, {args.repeat} rounds", flush=True)
    first_call = _timed(lambda: ws.run(d, grid=g, keep_maps=False), cpu=True)
    measures: dict[str, list] = {}  # what -> [(wall, cpu or None, LP wall, LP cpu)], one per round

    def add(what, wall, cpu, lp):
        measures.setdefault(what, []).append((wall, cpu, lp[0], lp[1]))

    best = {}
    with tempfile.TemporaryDirectory() as tmp:
        if args.cold:
            lp = lp_seconds_per_pose(d, poses)
            (wall, cpu), s = command(root, path, step, "csv", f"{tmp}/cold", tempfile.mkdtemp(dir=tmp))
            add("whole command, cold numba cache (csv)", wall, cpu, lp)
            if "load_s" in s.get("timings", {}):  # (a version before load_s compiled inside its sweep)
                add("  its load_s (numba compiling)", s["timings"]["load_s"], None, lp)
        for fmt in fmts:
            command(root, path, step, fmt, f"{tmp}/prime", None)  # numba's cache and the bytecode warm
        add("kernels in-process, first call", *first_call, lp_seconds_per_pose(d, poses))
        for _ in range(args.repeat):
            before = lp_seconds_per_pose(d, poses)
            kw = _timed(lambda: ws.run(d, grid=g, keep_maps=False), cpu=True)
            runs = {fmt: command(root, path, step, fmt, f"{tmp}/{fmt}", None) for fmt in fmts}
            after = lp_seconds_per_pose(d, poses)
            lp = ((before[0] + after[0]) / 2, (before[1] + after[1]) / 2)
            add("kernels in-process, warm", *kw, lp)
            for fmt, ((wall, cpu), s) in runs.items():
                add(f"whole command, warm ({fmt})", wall, cpu, lp)
                add(f"  its sweep_s ({fmt})", sweep_s(s), None, lp)
                if fmt not in best or wall < best[fmt][0]:
                    best[fmt] = (wall, s)
    lps = [r[2] for r in measures["kernels in-process, warm"]]
    print(f"  per-pose linprog {min(lps) * 1e3:.2f}-{max(lps) * 1e3:.2f} ms over the rounds "
          f"({np.median(lps) * g.size:.1f} s for the grid at the median)")
    for fmt, (wall, s) in best.items():
        if "timings" in s:
            t = s["timings"]
            load = f"load {t['load_s']:.3f} s, " if "load_s" in t else ""
            print(f"  {fmt}: timings of the fastest run: {load}sweep {t['sweep_s']:.3f} s, write {t['write_s']:.3f} s, "
                  f"pictures {t['pictures_s']:.3f} s, job total {t['total_s']:.3f} s; process {wall:.3f} s")
    print(f"  {'what (median round)':40s} {'wall [s]':>9s} {'poses/s':>10s} {'x LP (range)':>20s} {'CPU [s]':>8s} "
          f"{'x LP CPU':>9s}")
    for what, rounds in measures.items():
        ratios = sorted(lpw * g.size / w for w, _, lpw, _ in rounds)
        wall, cpu, _, lpc = sorted(rounds)[len(rounds) // 2]
        ratio_text = f"{np.median(ratios):7.1f} ({ratios[0]:.0f}-{ratios[-1]:.0f})"
        cpu_text = f"{cpu:8.3f} {lpc * g.size / cpu:9.1f}" if cpu else ""
        print(f"  {what:40s} {wall:9.3f} {g.size / wall:10,.0f} {ratio_text:>20s} {cpu_text}")
    return measures


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--step", type=float, default=0.14, help="IPAnema 3 grid step [m] (0.14: 154,440 poses)")
    ap.add_argument("--planar2-step", type=float, default=0.002, help="planar2's fine grid step [m]")
    ap.add_argument("--sample", type=int, default=300, help="poses of the per-pose LP baseline")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--root", help="checkout whose command is timed (default: this one)")
    ap.add_argument("--no-cold", dest="cold", action="store_false", help="skip the cold-cache command")
    args = ap.parse_args(argv)
    from cdpr_design.kernels import parallel

    rng = np.random.default_rng(0)
    print(f"kernel threads {parallel.threads()}, load average {os.getloadavg()[0]:.2f}; command from "
          f"{args.root or ROOT}")
    root = Path(args.root).resolve() if args.root else ROOT
    print("\nfixed costs of a process (best of --repeat, wall):")
    for what, t in floor_times(root, args.repeat):
        print(f"  {what:58s} {t:7.3f} s")
    bench_design("ipanema3", args.step, args, rng)
    bench_design("planar2", None, args, rng)
    bench_design("planar2", args.planar2_step, args, rng)
    d = spec.load(ROOT / "designs" / "ipanema3.yaml")
    print_writer_times(writer_times(d, ws.make_grid(d, args.step), args.repeat))


if __name__ == "__main__":
    main()
