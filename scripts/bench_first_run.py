#!/usr/bin/env python3
"""Benchmark: the first ``workspace`` run of every shipped design, cold and warm, against a baseline.

For every design in ``designs/*.yaml``, ``python -m cdpr_design workspace DESIGN --json`` in a
new process (:func:`bench_outputs.command`: wall time, and CPU time -- user + system -- of the
command's process and the processes it waits for):

1. cold: with ``NUMBA_CACHE_DIR`` a new, empty folder (every kernel the design uses compiled);
2. warm: the same folder again (loaded from numba's cache), ``--repeat`` times, the median;
3. the total compile: one new folder for all designs run one after the other, so that each
   kernel is compiled once, by the first design that needs it; the total is the sum over the
   designs of (that run's CPU - the design's warm CPU).

``--root DIR`` runs the same for another checkout first (e.g. the previous version: ``git
worktree add /tmp/base <commit>``), in the same run of this script, and prints the ratios
baseline / this checkout; it also compares their outputs (``workspace.csv`` and
``summary.json`` without its times): a change to how the kernels compile must not change
a number.  CPU time is the figure to trust on a shared machine; the load average is printed
before each checkout.

    python3 scripts/bench_first_run.py [--root DIR] [--repeat 3] [--designs planar2,ipanema3] [--no-total]

CPU is the command's process (the picture process, which it does not wait for, is not in it).

Figures (the 2-core development machine shared with five other sessions: load average 7-17
throughout, so the wall times are mostly waiting and the CPU times are inflated too).  Every
shipped design, ea1dd26 alone (``--repeat 2``, load average 5-9 at the start)::

    design       cold wall  cold CPU  warm wall  warm CPU
    cogiro         114.3 s    30.8 s     7.49 s    1.32 s
    crane4         173.8 s    59.3 s    18.12 s    7.57 s
    ipanema1       126.7 s    30.5 s    11.70 s    1.87 s
    ipanema2       115.7 s    26.9 s     9.28 s    1.06 s
    ipanema3       158.6 s    31.7 s     7.28 s    1.23 s
    planar2          9.1 s     1.0 s    10.29 s    0.91 s   (numpy engine: no kernel)
    planar4        118.3 s    23.7 s     9.17 s    1.17 s
    pointmass3      61.2 s    12.5 s    10.55 s    0.99 s
    sagging40      378.2 s   108.2 s    28.51 s    8.42 s
    cold compile of every kernel the designs use (one cache): 133.8 CPU-s

Before (``--root`` at ea1dd26) and after (the grid sweep's Python block, below), one run
(``--designs ipanema3,pointmass3,planar2 --repeat 2 --no-total``, load average 9.2 / 7.7)::

    design       cold wall          cold CPU           warm wall         warm CPU          outputs
    ipanema3     60.1 -> 47.5 s     28.0 -> 29.6 s     8.18 -> 3.93 s    1.27 -> 1.19 s    identical
    pointmass3   29.9 -> 17.8 s     13.1 -> 11.0 s     3.99 -> 3.99 s    0.99 -> 1.06 s    identical
    planar2       4.0 -> 4.4 s       1.0 -> 1.1 s      4.00 -> 4.22 s    1.02 -> 1.04 s    identical

The targets of issue 36 (IPAnema 3's first run <= 10 s on two cores, every kernel's compile
<= 30 s) are not met.  What was tried, each measured on IPAnema 3's kernels compiled in one
process from an empty cache (``workspaces.warm_up`` or the first ``workspaces.run``, CPU-s):

- the grid sweep's block in Python (``kernels.sweep._GridBlock``) instead of a compiled block
  around the compiled loop, which compiled the whole loop into its own module a second time:
  32.38 and 32.41 -> 28.96 and 28.83 (-11 %; two pairs, the four processes side by side), 32.9
  -> 30.1 in another pair; warm 2.99 -> 2.92 us a pose (one thread, best of 7); in the whole
  command above, one run each at different loads, within the noise.  Kept.
- ``hsm_two`` / ``hsm_one`` with one body and the closure flag read at run time instead of two
  inlined copies with the flag a constant: 34.2 -> 24.6, the largest gain found, but IPAnema 3's
  ``max_margin`` changed in its last bit (1654.7038865822271 -> 1654.703886582227, the CSV
  identical): a compile change must not change a number.  Dropped.
- the two copies as functions specialised on the flag (numba specialises a literal argument)
  instead of inlined: bit-identical, and 30.3 against 30.1: nothing.  Dropped.
- one loop function for every m - n with ``numba.literally(r)`` instead of four wrappers: numba's
  branch pruning does not reach into the inlined pose function, so every margin and QP method
  was compiled: 48.  Dropped.
- ``NUMBA_OPT`` 2 and 1 (LLVM's optimisation level, default 3): 20.8 and 19.7 against 21.5, warm
  2.64 and 3.48 us a pose: LLVM is not where the time goes.  A profile of the compile puts it in
  numba's own Python passes: type inference, lowering, and 15-18 % in copying the IR of the
  ``inline="always"`` functions (numba deep-copies every block with the whole scope, per inlined
  call and per level of nesting).  Dropped.
- without ``cdpr_design.numba_startup`` (numba's own cache loading): IPAnema 3 warm, 5
  interleaved pairs, CPU of all processes (``perf stat``), 2.37 (2.26-2.64) -> 3.02 (2.94-3.24)
  CPU-s; this script's warm CPU of the command 1.14 -> 1.68 (IPAnema 3), 0.84 -> 1.38
  (pointmass3), 0.90 -> 1.38 (IPAnema 2).  It matters to a user; it stays where it was.

Later (numba 0.68.1): where a cold compile goes, from numba's compile events and cProfile on
IPAnema 3's kernels: ``hsm_two`` about 30 % (two inlined copies of its body), ``_grid_loop_2``
about 20 %, ``project_two`` with its callees 15 %, ``row_buffers`` and ``make_scratch`` (compiled
alone because Python called them) 10 %.  Of the whole, numba's IR inlining (``inline="always"``)
is 3.2 of 25.6 CPU-s, 2.0 of them ``hsm_two``'s two copies; LLVM's optimisation at ``NUMBA_OPT=0``
saves 6-8 of about 28 (not an option: it is the kernels' speed).  A compiled function that takes
the scratch tuple (31 arrays) costs 0.3-0.4 CPU-s more to compile than the same body on its two
arrays (its arguments unpacked, and boxed again in its Python wrapper).  numba also compiles a
function once per *constant* argument it sees, and, for a variable first set from a constant in a
loop, once for the constant as well (``_finish`` with ``ok`` True and False, ``_inside`` with
``k`` = 0 and int64, ``_half_plane`` with -1 and int64, ``hsm_small._setup`` with the closure flag
True and False: ``kernel.signatures`` after a run).  Kept, each bit-identical (outputs compared
below; ``tension_qp`` has no fastmath, so IEEE arithmetic fixes its results whatever the code's
shape):

- ``make_scratch`` and ``row_buffers`` plain Python functions that numba compiles into the
  kernels calling them (``register_jitable``): the grid sweep's block and ``statics.tension``
  allocate with numpy and compile nothing for it;
- the eval's QP on the scratch's arrays (``null_space``, ``plane_projection``,
  ``line_projection``; the scratch-tuple forms stay for their other callers), and ``_finish``
  called once with a computed ``ok``.

Both, ``--root`` at cfe429a, ``--repeat 1 --no-total``, load average 6.8 (before) / 9.7 (after)::

    design       cold wall                cold CPU             warm wall              warm CPU      outputs
    ipanema3     151.5 -> 155.0 s         31.5 -> 26.3 s       16.13 -> 10.85 s       1.86 -> 1.54 s  identical
    pointmass3    89.2 -> 55.4 s          12.6 -> 9.3 s        17.09 -> 11.60 s       1.39 -> 1.22 s  identical
    planar4      161.2 -> 113.2 s         24.5 -> 17.5 s       14.31 -> 11.39 s       1.53 -> 1.31 s  identical
    planar2        9.7 -> 5.9 s            0.9 -> 0.9 s         9.06 -> 5.45 s        0.91 -> 0.91 s  identical

The same, another run (load average 8.5 before / 4.7 after; single warm runs, so their
differences are noise)::

    design       cold wall                cold CPU             warm wall              warm CPU      outputs
    ipanema2      97.5 -> 46.8 s          31.5 -> 24.0 s        4.06 -> 3.08 s        1.18 -> 1.51 s  identical
    cogiro        59.1 -> 25.4 s          31.9 -> 23.0 s        3.55 -> 3.41 s        1.62 -> 1.47 s  identical
    ipanema1      32.4 -> 28.0 s          30.0 -> 25.3 s        2.99 -> 4.46 s        1.61 -> 2.39 s  identical
    crane4        48.2 -> 53.0 s          45.8 -> 49.3 s        9.99 -> 8.99 s        6.60 -> 6.99 s  identical
    sagging40    110.6 -> 104.1 s        104.6 -> 97.4 s        9.24 -> 10.22 s       7.32 -> 8.61 s  identical
                 (a third run, load average 2.0 before / 4.1 after)

crane4 (its hanging sweep compiles ``row_buffers`` into its block either way) gains nothing.
After both, IPAnema 3's kernels compile into 20 functions (28 before), ``hsm_two`` the largest
(about 37 % of the compile by numba's events); still compiled twice: ``_setup`` (flag),
``_inside`` (``k`` 0 and int64) and ``_half_plane`` (-1 and int64).

Then (numba 0.68.1), each measured by numba's compile events (exclusive CPU per compiled
function, ``numba.core.event``) and by compiling one function alone from an empty cache
(``dispatcher.compile``, CPU-s, load average 6-11).  Kept, each bit-identical
(``workspace.csv`` and ``summary.json`` of IPAnema 3 compared; ``hsm_small`` keeps its
fast-math, so the code's shape could matter: outputs compared below):

- ``hsm_small._setup`` called once before the closure flag's branch, with the flag a variable
  (it was compiled once per constant value): ``hsm_two`` alone 10.3 -> 8.8 (means of three);
- ``hsm_one`` / ``hsm_two`` delegate to ``hsm_one_arrays`` / ``hsm_two_arrays`` on the
  scratch's arrays, which the sweeps' pose function calls (no 31-array tuple): 8.8 -> 6.7;
- their two bodies (one per constant flag) compiled functions instead of ``inline="always"``
  copies (numba's inlining deep-copies a body's IR block by block, each block with the whole
  scope): 6.7 -> 5.9;
- ``tension_qp.plane_projection``'s integers that reach ``_inside`` / ``_half_plane`` start as
  ``np.int64``, not literals (type inference saw the literal first and compiled each callee
  for it too): plane_projection alone 2.38 -> 2.04.

IPAnema 3's whole cold command, compile events: 23.3 (main) -> 19.5 CPU-s.  Then compiling in
two processes (``kernels/warm.py``, from ``workspaces.warm_up``): on a first run a
straight-cable sweep has a second process compile its pose's margin functions (``hsm_two_arrays``
and callees, about 6.5 CPU-s for IPAnema 3, plus about 1.5 s of imports) while this one
compiles the tension functions (basis factor, null space, QP: about 4 CPU-s) and then the CSV
formatter; the loop then links both from numba's cache.  IPAnema 3's command process: compile
events 19.5 -> 12.9 CPU-s, CPU of the command with the second process about 1 CPU-s more than
without.  Nothing is started when the kernels load from the cache (warm runs unchanged).

Before (06565fd) and after (the above), two runs of this script (``--repeat 1``), one after the
other, load average 2.6 rising to 10-15 (before) and 13.7 falling to 3 (after): the wall times
are mostly waiting for the other sessions' processes; cold CPU includes the second process::

    design       cold wall          cold CPU           warm wall          warm CPU
    cogiro       120.9 -> 220.9 s   29.1 -> 22.6 s     11.92 -> 22.10 s   1.34 -> 1.49 s
    crane4       258.0 -> 421.0 s   51.0 -> 42.8 s     26.07 -> 42.54 s   6.76 -> 5.75 s
    ipanema1     108.7 -> 173.1 s   24.5 -> 19.7 s     12.77 -> 26.56 s   1.76 -> 2.08 s
    ipanema2      85.9 -> 169.4 s   22.1 -> 22.9 s      4.95 -> 14.87 s   1.18 -> 1.55 s
    ipanema3      88.9 -> 108.8 s   22.9 -> 22.6 s      9.91 -> 12.80 s   1.53 -> 1.84 s
    planar2        9.2 -> 9.4 s      0.9 -> 1.0 s      11.63 -> 5.93 s    1.04 -> 1.06 s
    planar4       89.1 -> 57.6 s    18.5 -> 18.5 s     14.38 -> 8.21 s    1.80 -> 1.51 s
    pointmass3    41.0 -> 47.8 s     8.6 -> 9.8 s       4.69 -> 13.91 s   1.19 -> 1.61 s
    sagging40    447.8 -> 325.2 s  112.2 -> 113.0 s    37.10 -> 19.52 s   6.78 -> 8.33 s
    cold compile of every kernel the designs use (one cache): 129.8 -> 127.8 CPU-s

IPAnema 3's cold command alone (``/usr/bin/time``: wall, and user + sys CPU of it and the
processes it waited for), two interleaved pairs, load average 3.1-3.9 (other sessions on both
cores): before 29.3 s / 26.5 CPU-s and 44.7 s / 27.8 CPU-s, after 25.4 s / 23.1 CPU-s and
30.7 s / 23.5 CPU-s; the same ``workspace.csv``.

Under these loads the command-level CPU figures move by 10-20 % between runs of the same code
(pointmass3, sagging40 and planar2 have no changed kernel); the per-function figures above
are the reliable ones.  The targets (IPAnema 3 <= 10 s, every kernel <= 30 s) are still not
met: the sweep's loop (``_grid_loop_2``, 5-6 CPU-s: numba links every callee's IR into it and
LLVM optimises it all again) is compiled after both processes, and the sagging kernels
(sagging40's compile alone is about 105 of the 128 CPU-s) were not touched here.

Then (2026-11-28) two kernels that chose their method at run time, so compiled every method:
the sagging cables' fixed point now takes ``redundant`` (None for m = n: numba compiles it per
argument type and prunes the ``is None`` branch before typing it), and the hanging effector's
rotated statics one loop per m - n chosen in Python, as the grid sweep's.  Compile events:
sagging40 89.4 -> 55.9 CPU-s, crane4 44.1 -> 13.9.  ``--root`` at 86a3f90 (before both; outputs
identical for every design), then this checkout alone after the second, ``--repeat 1``, two idle
cores (load average 1.2-1.9)::

    design       cold wall         cold CPU          warm wall        warm CPU
    cogiro       18.5 -> 17.6 s    22.3 -> 21.6 s    2.16 -> 2.16 s   1.60 -> 1.58 s
    crane4       48.7 -> 22.2 s    50.5 -> 24.4 s    6.36 -> 6.97 s   8.17 -> 8.76 s
    ipanema1     17.8 -> 17.3 s    20.7 -> 22.2 s    2.52 -> 2.55 s   2.32 -> 2.27 s
    ipanema2     16.6 -> 17.7 s    20.9 -> 21.9 s    1.91 -> 2.04 s   1.45 -> 1.49 s
    ipanema3     18.6 -> 16.4 s    22.7 -> 20.5 s    2.38 -> 2.22 s   1.89 -> 1.77 s
    planar2       1.7 -> 1.7 s      1.1 -> 1.0 s     1.70 -> 1.49 s   1.07 -> 0.97 s
    planar4      14.4 -> 15.6 s    17.4 -> 18.6 s    1.79 -> 1.76 s   1.43 -> 1.40 s
    pointmass3    8.7 -> 8.9 s      8.5 -> 8.7 s     1.50 -> 1.39 s   1.14 -> 1.07 s
    sagging40    88.6 -> 58.5 s    91.6 -> 61.3 s    5.62 -> 5.62 s   8.01 -> 8.16 s
    cold compile of every kernel the designs use (one cache): 132.2 -> 83.6 CPU-s

The targets are still not met: IPAnema 3's first run is 16.4 s on two idle cores, every kernel
84 CPU-s.  What is left is numba linking and optimising every callee again into each separately
compiled caller (IPAnema 3's ``_grid_loop_2`` 5-6 CPU-s; the sagging chain's six levels about 26
of sagging40's 56).

Then (the same day, later) two more, each measured by compile events first: ``hsm_small``'s
one- and two-redundant-cable bodies compiled once with the closure flag a variable (IPAnema 3's
margins 7.6 -> 4.8 CPU-s alone; this is the change dropped above for a last-bit change in
``max_margin``, taken now: with fast-math the rounding of a sum depends on the code around it,
the 1-ulp difference is in the summary's ``max_margin`` of IPAnema 3 only, every CSV is
identical, and the first run of every design with one or two redundant cables gains 2-3 s), and
the sagging chain's single-call-site functions folded into their callers (sagging40 60.5 ->
40.0 CPU-s of compile events).  ``--root`` at c86959e (before both), ``--repeat 1``, two idle
cores (load average 1.1)::

    design       cold wall         cold CPU          warm wall        warm CPU
    cogiro       19.1 -> 11.5 s    22.6 -> 14.7 s    2.13 -> 1.84 s   1.61 -> 1.50 s
    crane4       25.7 -> 16.4 s    26.0 -> 18.5 s    8.17 -> 5.84 s   8.55 -> 7.70 s
    ipanema1     19.7 -> 13.3 s    23.9 -> 17.5 s    2.36 -> 2.11 s   2.22 -> 2.00 s
    ipanema2     16.0 -> 13.5 s    20.3 -> 17.0 s    1.76 -> 1.98 s   1.40 -> 1.47 s
    ipanema3     17.6 -> 14.3 s    21.8 -> 18.2 s    2.12 -> 1.78 s   1.69 -> 1.48 s   (max_margin: 1 ulp)
    planar2       1.4 -> 1.7 s      0.9 -> 1.0 s     1.62 -> 1.62 s   1.00 -> 0.98 s
    planar4      14.5 -> 12.1 s    17.0 -> 15.0 s    1.96 -> 1.64 s   1.52 -> 1.25 s
    pointmass3   10.8 -> 9.6 s     10.5 -> 9.3 s     1.80 -> 1.56 s   1.30 -> 1.20 s
    sagging40    62.0 -> 52.2 s    63.8 -> 54.8 s    5.55 -> 4.86 s   8.21 -> 7.22 s
    cold compile of every kernel the designs use (one cache): 88.3 -> 76.5 CPU-s

(The before column of the same code moves by about 10 % between runs: IPAnema 3 16.4 s
earlier, 17.6 s here.)  IPAnema 3's first run, on a timeline of compile events: 1.1 s to
the first compile (imports, the spec), the tension functions 4 s and the CSV formatter 1.6 s in
this process while the other compiles the margins (started at 1.9 s, done at 7.8 s), then the
loop alone, 5.2 s (numba's IR inlining 1.2, LLVM 2.9), then the sweep and the files, 0.8 s:
with both processes busy until the loop, the loop is what stands between this and 10 s.
Tried and dropped here: the facet body inlined in numba's IR once (5.6 against 4.6 CPU-s),
``NUMBA_LOOP_VECTORIZE=0`` and ``NUMBA_OPT`` 1-2 (at most 10 % of the loop, and a process-wide
switch would make a kernel's rounding depend on which process filled the cache).

Then two more thin levels folded (sagging's ``_distribute`` / ``_min_norm`` over the QP, and
``hsm_one_arrays`` / ``hsm_two_arrays``, whose setup and facets the other process now compiles).
``--root`` at b414a3d, ``--repeat 1``, two idle cores (load average 1.2; the machine ran about
10 % slower that day than the day before: the same b414a3d gave IPAnema 3 15.1 s, against 14.3)::

    design       cold wall         cold CPU          warm wall        warm CPU
    cogiro       16.1 -> 12.6 s    20.2 -> 16.6 s    2.04 -> 1.55 s   1.53 -> 1.21 s
    crane4       19.8 -> 18.5 s    22.2 -> 20.9 s    6.63 -> 6.06 s   8.54 -> 7.78 s
    ipanema1     15.8 -> 13.8 s    20.1 -> 17.4 s    2.18 -> 2.37 s   2.05 -> 2.19 s
    ipanema2     15.5 -> 13.1 s    19.6 -> 16.6 s    2.14 -> 1.74 s   1.57 -> 1.32 s
    ipanema3     15.1 -> 13.8 s    19.4 -> 17.4 s    1.93 -> 1.78 s   1.61 -> 1.48 s
    planar2       1.3 -> 1.4 s      0.8 -> 0.8 s     1.45 -> 1.61 s   1.02 -> 1.09 s
    planar4      12.0 -> 11.6 s    14.5 -> 14.2 s    1.92 -> 1.67 s   1.52 -> 1.37 s
    pointmass3   10.5 -> 9.8 s     10.1 -> 9.7 s     1.65 -> 1.53 s   1.32 -> 1.17 s
    sagging40    49.6 -> 47.2 s    52.3 -> 49.5 s    5.22 -> 4.93 s   7.78 -> 7.15 s
    cold compile of every kernel the designs use (one cache): 69.4 -> 80.4 CPU-s

Every output identical.  The total is one sequential run per checkout and within its noise:
a second pair (every design in one new cache, all CPU of the commands, pictures drawn in
them) gave 110.1 -> 112.6 CPU-s.  Measured and dropped: ``make_sag_scratch`` compiled into its
callers (within the noise), the QP's thin levels below ``_min_norm`` folded (three pairs, no
gain), the margins' setup moved to this process (this one then finished last), and a cheaper
tension function first so that the other process starts sooner (numba's own first-compile
start-up, about 0.6 s, goes to whichever comes first).

Then the grid loop of m - n = 1, 2 given the pose's five functions as pointers
(``kernels/pointers.py``: the C wrappers of their compiled versions), so that it compiles alone,
while the other process still compiles the margins, and once for both redundancies.  Measured
on its own first, the loop's compile shrank less than expected (IPAnema 3's loop 4.45 -> 3.61
CPU-s in numba's pipeline: numba's own inlining and typing of the loop's body stay); the gain is
that it no longer waits.  A first version compiled the pointers as ``cfunc``s of their own, and
the every-kernel total rose 73.3 -> 83.2 CPU-s (the other loops still compile the functions as
before); the compiled functions' own wrappers compile nothing twice.  ``--root`` at 247171b,
``--repeat 1``, two idle cores (load average 0.9-1.2)::

    design       cold wall         cold CPU          warm wall        warm CPU
    cogiro       14.4 -> 12.1 s    18.3 -> 16.4 s    2.01 -> 2.19 s   1.57 -> 1.72 s
    crane4       19.9 -> 22.1 s    22.1 -> 24.3 s    6.65 -> 5.46 s   8.41 -> 7.36 s
    ipanema1     14.6 -> 9.2 s     18.4 -> 12.8 s    2.26 -> 2.26 s   2.10 -> 2.04 s
    ipanema2     14.8 -> 10.1 s    19.1 -> 14.0 s    1.94 -> 1.85 s   1.45 -> 1.40 s
    ipanema3     14.6 -> 10.4 s    17.9 -> 14.4 s    2.25 -> 2.22 s   1.86 -> 1.83 s
    planar2       1.7 -> 1.6 s      1.1 -> 1.0 s     1.66 -> 1.55 s   1.04 -> 0.75 s
    planar4      14.2 -> 9.5 s     17.2 -> 12.4 s    1.98 -> 1.75 s   1.55 -> 1.37 s
    pointmass3   10.6 -> 10.5 s    10.4 -> 10.3 s    1.61 -> 1.96 s   1.23 -> 1.49 s
    sagging40    51.0 -> 47.9 s    52.8 -> 49.8 s    5.09 -> 4.17 s   6.69 -> 6.07 s
    cold compile of every kernel the designs use (one cache): 73.8 -> 75.6 CPU-s

Every output identical.  crane4, pointmass3 and sagging40 do not use the changed loop: their
moves are the noise.  Four interleaved pairs of IPAnema 3's first run: 15.46 / 13.65 / 14.22 /
16.22 -> 11.25 / 10.79 / 11.51 / 11.61 s with the cfuncs, three with the wrappers 14.55 / 14.90 /
14.04 -> 10.40 / 10.85 / 10.81 s; its sweep 0.12 s either way (56,000 poses, two threads, three warm runs each).  Where
its first run goes now: 1.4 s to the first compile, the tension functions to 4.9 s, the CSV
formatter to 6.5 s, the loop (3.7 CPU-s, with the structure matrix it calls) to 10.2 s, then
the sweep and the files; the other process is done with the margins at about 7 s.

Then (2026-11-28, later) three changes on that timeline, each timed on it first:

- the loop is given the structure matrix as a sixth pointer and only the twelve scratch arrays
  its pose uses (``pose.SmallScratch``, not the 31-array tuple): the loop alone, compiled for
  IPAnema 3's types in a new process, 3.05 / 3.26 / 3.40 -> 2.06 / 2.08 / 2.22 CPU-s;
- the shares rebalanced: the other process compiles the null basis, the margins' setup and
  facets, the structure matrix and the chunk statistics, this one the projection, the basis
  factorisation and the CSV formatter (moving the formatter to the other process instead made
  it finish 1.5 s after this one);
- the other process started before this one knows whether it is a first run, and stopped when
  the first function asked for here loads (``warm._first_run``): it then imports numba while
  this process does, 0.8 s sooner.  A warm run pays for it on the other core: IPAnema 3, eight
  interleaved warm pairs, wall 2.13 -> 2.19 s (median), CPU of the command and what it waits for
  1.79 -> 2.25 CPU-s.

Interleaved cold pairs of IPAnema 3 (``NUMBA_CACHE_DIR`` new each run, ``--quiet``; the machine's
speed drifted by up to 40 % between batches, the same code taking 6.4 or 9.3 s): b8bc845 (the
start of this session) against the first two changes, six pairs, medians 11.5 -> 9.4 s; those
against the third as well, five pairs, 8.9 -> 8.1 s.  Timeline of one first run after all three
(compile events, both processes)::

    0.84  other process started
    1.36- 2.17  basis_factor (with numba's own start-up)   | 1.75- 2.70 null_space (with it)
    2.19- 4.21  plane_projection                            | 2.72- 3.52 facet_setup
    4.23- 5.40  format_rows (CSV)                           | 3.53- 5.87 facets_two
    5.41- 7.33  _grid_loop_small                            | 5.90- 6.50 structure_matrix
                                                            | 6.51- 6.74 chunk_stats, exit
    8.08  exit (sweep, files, pictures)

(there the probe was still ``basis_factor``; it is the projection now, the function whose code
is this m - n's own, so that a process sweeping m - n = 2 and then 1 has another process for
each).  ``--root`` at b8bc845, ``--repeat 1``, two idle cores (load average 1.0-1.2; the after
half ran about 20 % faster than the before half, as the unchanged planar2, pointmass3 and
sagging40 show)::

    design       cold wall         cold CPU          warm wall        warm CPU
    cogiro       11.0 -> 7.6 s     14.8 -> 12.7 s    2.06 -> 1.82 s   1.57 -> 1.80 s
    crane4       28.4 -> 23.5 s    30.4 -> 25.9 s    6.41 -> 6.48 s   8.34 -> 8.49 s
    ipanema1     11.6 -> 9.4 s     16.6 -> 15.7 s    2.64 -> 2.45 s   2.40 -> 2.76 s
    ipanema2     10.7 -> 8.6 s     14.8 -> 14.2 s    1.84 -> 2.02 s   1.45 -> 2.05 s
    ipanema3     11.0 -> 8.1 s     15.3 -> 14.0 s    2.20 -> 1.60 s   1.80 -> 1.65 s
    planar2       1.8 -> 1.3 s      1.0 -> 0.8 s     1.86 -> 1.26 s   1.00 -> 0.75 s
    planar4      10.8 -> 6.7 s     14.0 -> 10.9 s    1.96 -> 1.79 s   1.57 -> 1.88 s
    pointmass3   12.8 -> 10.2 s    12.2 -> 10.1 s    1.76 -> 1.37 s   1.35 -> 0.98 s
    sagging40    56.5 -> 48.2 s    58.0 -> 50.5 s    4.27 -> 4.13 s   6.12 -> 6.11 s
    cold compile of every kernel the designs use (one cache): 75.1 -> 77.7 CPU-s

Every output identical.  IPAnema 3's first runs on two cores since the third change: 6.4-9.5 s
in the eleven runs above (the pairs and this table), 9.3 and 10.1 s in two with the compile-event
logger on in a slow phase of the machine; the every-kernel total is not reduced (the other process's own start-up is in it):
sagging40's chain of separately compiled functions, each optimised again with its callees in
every caller, is most of it.

Then (2026-11-29) the sagging kernels and crane4's loop, each measured first by numba's compile
events of the design's first ``workspace`` (CPU-s; outputs compared each time):

- the sagging blocks call the fixed point's loop (``_iterate``) through a C function pointer
  (``sagging.fixed_point``), not linked into each block's module, and the converged pose's
  verdict is a function of its own (``_evaluate``: a square robot's block no longer copies the
  redundant verdict's body before pruning it): sagging40 21.4 -> 18.5.  The next level
  (``_fixed_map``) through a pointer as well: no gain and a slower sweep; dropped;
- the fixed point and everything below it that takes arrays compiled without reference counting
  (the Newton step's Jacobian in the scratch): 18.5 -> 17.0, and sagging40's sweep 1.78 -> 1.06 s;
- the sagging blocks' loops without reference counting too, their buffers from a Python
  ``RowBlock``: 17.0 -> 16.0;
- the loop over hanging orientations for one or two redundant cables given the pose's six
  functions as pointers, as the grid's: crane4's loop 2.5 -> 0.8, its first run 5.6 -> 4.3.

This machine ran about twice as fast as in the runs above (c1bd809's IPAnema 3 3.4 s cold here,
8.1 s there).  ``--root`` at c1bd809 (before the four), ``--repeat 2``, two idle cores (load
average 2.4 / 1.5; the after half about 10 % slower than the before, as the unchanged designs
show)::

    design       cold wall         cold CPU          warm wall        warm CPU
    cogiro        3.5 -> 3.6 s      6.1 -> 6.3 s     0.87 -> 0.88 s   0.90 -> 0.94 s
    crane4       11.4 -> 6.7 s     12.4 -> 7.8 s     2.30 -> 2.42 s   3.14 -> 3.27 s
    ipanema1      3.4 -> 3.8 s      5.9 -> 6.6 s     0.98 -> 1.03 s   1.13 -> 1.19 s
    ipanema2      3.2 -> 3.6 s      5.5 -> 6.3 s     0.76 -> 0.86 s   0.78 -> 0.89 s
    ipanema3      3.4 -> 3.7 s      6.0 -> 6.4 s     0.87 -> 0.92 s   0.95 -> 1.01 s
    planar2       0.6 -> 0.6 s      0.4 -> 0.4 s     0.59 -> 0.65 s   0.39 -> 0.43 s
    planar4       2.7 -> 3.1 s      4.7 -> 5.4 s     0.73 -> 0.83 s   0.80 -> 0.90 s
    pointmass3    4.4 -> 4.8 s      4.4 -> 4.7 s     0.69 -> 0.75 s   0.54 -> 0.59 s
    sagging40    22.1 -> 18.4 s    23.8 -> 19.3 s    2.58 -> 1.89 s   4.12 -> 2.69 s
    cold compile of every kernel the designs use (one cache): 34.1 -> 24.5 CPU-s

Every output identical.  And on the same machine, the version issue 36 was filed against
(ea1dd26, whose every-kernel total was "about 60 s" then) against this one, ``--repeat 1``, two
idle cores (load average 0.8 / 1.1)::

    design       cold wall         cold CPU          warm wall        warm CPU
    cogiro       11.4 -> 3.9 s     11.3 -> 6.6 s     0.68 -> 0.97 s   0.49 -> 1.01 s
    crane4       21.6 -> 7.2 s     22.6 -> 8.3 s     2.30 -> 2.54 s   3.18 -> 3.40 s   (*)
    ipanema1     11.6 -> 3.9 s     11.7 -> 6.7 s     0.89 -> 1.10 s   0.82 -> 1.26 s
    ipanema2     11.5 -> 3.8 s     11.4 -> 6.5 s     0.63 -> 0.90 s   0.45 -> 0.93 s
    ipanema3     11.3 -> 3.8 s     11.2 -> 6.5 s     0.71 -> 0.95 s   0.56 -> 1.01 s   (*)
    planar2       0.7 -> 0.7 s      0.4 -> 0.4 s     0.66 -> 0.66 s   0.43 -> 0.43 s
    planar4       9.2 -> 3.1 s      9.1 -> 5.4 s     0.59 -> 0.83 s   0.44 -> 0.89 s
    pointmass3    5.2 -> 4.9 s      5.1 -> 4.9 s     0.57 -> 0.79 s   0.40 -> 0.62 s
    sagging40    44.8 -> 18.9 s    46.8 -> 19.8 s    2.82 -> 1.89 s   4.71 -> 2.70 s
    cold compile of every kernel the designs use (one cache): 57.8 -> 24.6 CPU-s

(*) outputs differ by later fixes, not by how the kernels compile: crane4's poses rejected for
their tilt have an empty margin now (25765f0), IPAnema 3's ``max_margin`` is 1 ulp off (the
margins' closed forms with the closure flag a variable, above).  The warm runs of the designs
with numba kernels cost 0.2-0.3 s and 0.4-0.5 CPU-s more than at ea1dd26: numba loads its cache
its own way again (issue 36's item 6, measured when ``numba_startup`` went) and a run that might be
a first one starts the other process until it knows (above).
"""

from __future__ import annotations

import argparse
import filecmp
import json
import os
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_outputs import ROOT, command  # noqa: E402  (the command in a new process, timed)


def run(root: Path, design: str, out: Path, cache: Path) -> tuple[float, float]:
    """(wall, CPU) [s] of ``workspace`` on ``root``'s ``designs/<design>.yaml`` with numba's cache in ``cache``."""
    (wall, cpu), _ = command(root, root / "designs" / f"{design}.yaml", None, "csv", str(out), str(cache))
    return wall, cpu


def first_runs(root: Path, designs: list[str], tmp: Path, repeat: int, total: bool) -> dict:
    """Per design: ``cold`` and ``warm`` (wall, CPU) [s], and ``out`` (the cold run's folder);
    with ``total``, ``compile`` (CPU [s] of the design's kernels not compiled by an earlier design)."""
    res = {}
    for name in designs:
        cache = Path(tempfile.mkdtemp(dir=tmp))
        out = tmp / f"{name}.out"
        cold = run(root, name, out, cache)
        warm = [run(root, name, tmp / "warm.out", cache) for _ in range(repeat)]
        res[name] = {"cold": cold, "out": out,
                     "warm": (statistics.median(w for w, _ in warm), statistics.median(c for _, c in warm))}
        print(f"  {name:12s} cold {cold[0]:6.1f} s wall {cold[1]:6.1f} CPU-s, warm {res[name]['warm'][0]:5.2f} s "
              f"wall {res[name]['warm'][1]:5.2f} CPU-s", flush=True)
    if total:
        cache = Path(tempfile.mkdtemp(dir=tmp))
        for name in designs:
            res[name]["compile"] = max(0.0, run(root, name, tmp / "total.out", cache)[1] - res[name]["warm"][1])
    return res


def same_outputs(a: Path, b: Path) -> bool:
    """``workspace.csv`` byte-identical and ``summary.json`` equal without its times (``timings``,
    ``elapsed_s``)."""
    def summary(folder):
        s = json.loads((folder / "summary.json").read_text())
        for key in ("timings", "elapsed_s"):
            s.pop(key, None)
        return s

    return filecmp.cmp(a / "workspace.csv", b / "workspace.csv", shallow=False) and summary(a) == summary(b)


def table(designs: list[str], before: dict | None, after: dict) -> None:
    """The cold / warm table (and the total compile), with ratios before / after when there is a before."""
    def cell(res, name, what, i):
        return f"{res[name][what][i]:.2f}" if what == "warm" else f"{res[name][what][i]:.1f}"

    cols = [("cold wall", "cold", 0), ("cold CPU", "cold", 1), ("warm wall", "warm", 0), ("warm CPU", "warm", 1)]
    print(f"\n{'design':12s}" + "".join(f"{h:>24s}" for h, _, _ in cols) + ("   outputs" if before else ""))
    for name in designs:
        row = f"{name:12s}"
        for _, what, i in cols:
            text = cell(after, name, what, i)
            if before:
                text = f"{cell(before, name, what, i)} -> {text} ({before[name][what][i] / after[name][what][i]:.1f}x)"
            row += f"{text:>24s}"
        if before:
            row += "   identical" if same_outputs(before[name]["out"], after[name]["out"]) else "   DIFFER"
        print(row)
    if "compile" in after[designs[0]]:
        total = sum(after[n]["compile"] for n in designs)
        text = f"{total:.1f} CPU-s"
        if before:
            was = sum(before[n]["compile"] for n in designs)
            text = f"{was:.1f} -> {text} ({was / total:.1f}x)"
        print(f"\ncold compile of every kernel the designs use (one cache, CPU - warm CPU): {text}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", help="baseline checkout, timed first (default: none)")
    ap.add_argument("--designs", help="comma-separated design names (default: every designs/*.yaml)")
    ap.add_argument("--repeat", type=int, default=3, help="warm runs per design (the median is shown)")
    ap.add_argument("--no-total", dest="total", action="store_false", help="skip the total compile")
    args = ap.parse_args(argv)
    designs = args.designs.split(",") if args.designs else sorted(p.stem for p in (ROOT / "designs").glob("*.yaml"))
    with tempfile.TemporaryDirectory() as tmp:
        results = {}
        for label, root in ([("before", Path(args.root).resolve())] if args.root else []) + [("after", ROOT)]:
            print(f"{label}: {root}, load average {os.getloadavg()[0]:.2f}", flush=True)
            folder = Path(tmp) / label
            folder.mkdir()
            results[label] = first_runs(root, designs, folder, args.repeat, args.total)
        table(designs, results.get("before"), results["after"])


if __name__ == "__main__":
    main()
