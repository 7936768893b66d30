"""The exact kernels' arguments and scratch in named bundles (:func:`.taylor.taylor_run`, the
tracking kernels, and the ``"expm"`` propagator's :mod:`.kernels`).

Named tuples: the field order is the contract. A kernel that receives a bundle from Python
unpacks it by position (it arrives as a plain tuple, below); the named ones a kernel builds
and hands on are read by field (``pk.PB``), with the same machine work. Arrays in a bundle
are shared, not copied: what a kernel changes in place (the contact state ``Call.s``, the
stiffness ``System.kc``, the outputs) the caller sees. From Python they cross into numba as plain
tuples (``tuple(bundle)``, in this order; built once per call in
:meth:`.taylor.TaylorIntegrator.run`, once per contact state in
:meth:`.exact.ExactIntegrator.stacks`): numba's dispatch costs about 0.4 us more per named
tuple than per plain one (measured on ``advance_state``, which the ``"expm"`` propagator
calls every step: 6 % of a gear rattle's run). Inside, :func:`.taylor.taylor_run` builds the
named ones it hands on once per call (:func:`.taylor._scratch`, :func:`.taylor._tracked`).
"""

from __future__ import annotations

from collections import namedtuple

#: The frozen system: ``M^-1 K0`` and ``M^-1 C0`` (n, n), the rows ``M^-1 w_e`` (``U``) and
#: the gap rows ``W`` (nc, n), ``W`` by its nonzeros (``wptr``, ``widx``, ``wval``: CSR), the
#: contacts' stiffness ``kc`` (changed in place by time events), damping ``cc`` and offsets
#: ``off``, and ``M^-1`` times the force basis ``MinvU`` (n, m).
System = namedtuple("System", "MK0 MC0 U W wptr widx wval kc cc off MinvU")

#: The call: the generalised force ``F`` (n_steps + 1, m) on the output grid, the state ``x``
#: and contact state ``s`` (both written back at the end), the output steps ``k0 ..
#: n_steps - 1``, ``k_org`` (row ``j`` at time ``(j + k_org) dt``), the output step ``dt``, the
#: piece bound ``h_max`` and term scale ``tscale`` over every state, the term table
#: ``terms``, the tie window ``tie`` (s) and ``max_events`` per output step.
Call = namedtuple("Call", "F x s k0 n_steps k_org dt h_max terms tscale tie max_events")

#: The outputs: rows ``X`` (state) and ``S`` (contact state), the event rows ``EV`` from row
#: ``n_ev`` on (grown by the kernel, which returns the larger array) and the work ``counts``.
Out = namedtuple("Out", "X S EV n_ev counts")

#: Scheduled stiffness changes (alternating mesh stiffness): times ``t`` from step 0 (sorted),
#: contacts ``e``, new stiffnesses ``k``, and ``pos`` (1,), the next entry (advanced in place).
Schedule = namedtuple("Schedule", "t e k pos")

#: Turning geometry (:class:`~gearmodal.integrate.periodic.Periodic`; empty arrays for a
#: frozen system): the input speed ``om`` (rad/s) and azimuth ``psi0`` at time 0, the
#: harmonics and their parts, and ``GT`` (H1, n, m) the turning harmonics of ``M^-1`` times
#: the load columns.
Turning = namedtuple("Turning", "om psi0 harm tcols krows urows ZK ZC tc_idx TW TOFF TU GT")

#: Per-contact-state spectral bounds (:class:`~gearmodal.integrate.taylor.StateBound`):
#: ``reach``, whether they are on (``per_state``), their arrays and the table of states met.
Bound = namedtuple("Bound", "reach per_state Ksym Wl km cb kappa keys vals")

#: Loads on their own time structure: knot times ``TL`` (nk,) from step 0 (none, or the first
#: at or before 0 and the last at or after the call's end: numba does not check) and values
#: ``FL`` (nk, mL) there, linear in between (a load series on its knots, a callable on its load
#: step), acting through ``MinvUL`` (n, mL) and, turning, ``GTL`` (H1, n, mL); harmonic loads
#: ``M^-1 F = Re sum_j HX_j exp(i HNU_j t)``: ``HX`` (nh, n) complex, ``HNU`` (nh,) rad/s.
Loads = namedtuple("Loads", "TL FL MinvUL GTL HX HNU")

#: Exact peaks (:class:`~gearmodal.integrate.peaks.PeakTracker`): on or off (``track``), the
#: open episodes ``EP`` (contacts, 2: peak, time), the peak bins ``PB`` (n_bins, contacts +
#: channels, 5: value, time, and with the turning points a spring channel's load integrals) of
#: ``pbin`` s, the pending pieces ``PC``, ``PM``, ``PN``, and ``t_call``: this call's start
#: (absolute times).
Peaks = namedtuple("Peaks", "track EP PB pbin PC PM PN t_call")

#: Sparse rows (CSR): row ``j``'s columns ``idx[ptr[j]:ptr[j + 1]]`` and values ``val``.
Sparse = namedtuple("Sparse", "ptr idx val")

#: Spring channels (a bearing's radial force): the springs' sparse rows ``rows``
#: (:data:`Sparse`) with stiffness ``sk`` and damping ``sc``, channels ``chp`` (n_ch, 2) of
#: row indices (a second index -1: one row).
Channels = namedtuple("Channels", "rows sk sc chp")

#: Exact turning points (:class:`~gearmodal.integrate.turns.TurnPoints`): the contact
#: channels ``TCH`` and their weights ``TCW``, each channel's state ``TS``, and the rows
#: ``TP`` from row ``ntp`` (grown by the kernel, which returns the larger array): a turning
#: point ``(time, channel, value)``, a change of a channel's level bin ``(time,
#: -(channel + 1), bin, input revolutions)``.
Turns = namedtuple("Turns", "TCH TCW TS TP ntp")

#: A run advanced over several calls: ``carry`` (7,) (written at the end; empty for a call
#: of its own), the last call's state matrices ``MKC`` and ``acc``, and ``t_span`` (2,) the
#: call's start and end times when the caller gives them (empty otherwise).
Chain = namedtuple("Chain", "carry MKC acc t_span")

#: What a turning piece's series reads (:func:`~.taylor._coefficients`): the turning
#: coordinates ``tcols``, the rows ``urows`` the turning contacts act on, the geometry's
#: ``TW`` and ``TU`` (:data:`Turning`), and its scratch: the product's input row
#: ``y``, the exponential series ``E`` and its lengths ``EL``, the Cauchy products ``Y``,
#: ``Yd`` and the turning coordinates' rows ``Bt``, the turning contacts' offsets ``OFS``,
#: stiffness ``kt``, damping ``ct`` and state ``closed``, their penetration, rate and force
#: series ``P``, ``PD``, ``FT``, the turning loads ``GV`` and their rates ``GVS``, the harmonic
#: loads' rows ``HF`` and the kept turning columns ``zsrc``.
TurningWork = namedtuple(
    "TurningWork", "tcols urows TW TU y E EL Y Yd Bt OFS kt ct closed P PD FT GV GVS HF zsrc")

#: What the tracking reads of the contacts (:func:`~.taylor._track_peaks`,
#: :func:`~.taylor._track_turns`): the contact state ``s``, the contacts that jumped at the
#: piece's start ``jumped``, stiffness ``kc``, damping ``cc``, offsets ``off``, the gap rows
#: ``rows`` (:data:`Sparse`), the turning contacts ``tc_idx`` and their force series ``FT``.
ContactRows = namedtuple("ContactRows", "s jumped kc cc off rows tc_idx FT")

#: A polynomial search's scratch (:func:`~.taylor.poly_max`, :func:`~.taylor.poly_turns`; ``e``
#: also the first bounds' of :func:`~.taylor._low_bound` and :func:`~.taylor._upper`): ``d``,
#: ``e`` of the series' width, ``wflat`` the subdivision's rows, ``stk`` its stack.
Search = namedtuple("Search", "d e wflat stk")

#: The peak search's scratch (:func:`~.taylor._track_peaks`): the coordinates' tail sums
#: ``tq``, ``td`` of the first bound, the force series ``fx``, ``fy``, a radial channel's
#: square ``P``, and ``tmp``.
PeakWork = namedtuple("PeakWork", "tq td fx fy P tmp")

#: The turning channels (:class:`~gearmodal.integrate.turns.TurnPoints`): contact channels
#: ``TCH`` and their weights ``TCW``, and every channel's state ``TS``.
TurnChannels = namedtuple("TurnChannels", "TCH TCW TS")

#: The turning points' scratch (:func:`~.taylor._track_turns`): the series ``fx``, ``fy``,
#: ``P``, ``tmp``, the extrema ``taus``, the input's speed ``spd`` and revolutions ``rev``,
#: and the load integrals' nodes, weights, bins and values ``XN``, ``WN``, ``BN``, ``AQ``.
TurnWork = namedtuple("TurnWork", "fx fy P tmp taus spd rev XN WN BN AQ")


#: A piece's states (:func:`~.taylor.taylor_run`'s phases): positions and velocities at its
#: start ``q``, ``v`` and end ``qb``, ``vb``, the gaps and their rates there (``ga``, ``ra``,
#: ``gb``, ``rb``) and an output row's state ``qo``, ``vo``.
PieceState = namedtuple("PieceState", "q v qb vb ga ra gb rb qo vo")

#: The force terms of the series (:func:`~.taylor.taylor_run`): ``M^-1 F`` of the force grid
#: at the stretch start ``gF`` and its rate ``gS``, at the piece's start ``g0`` with the rate
#: ``gR``; the turning load harmonics of the grid ``VA``, ``VS`` and at the piece's start ``GV``,
#: ``GVS``; the loads on their own knots ``gLa``, ``gLs`` and harmonics ``VLa``, ``VLs``.
Forcing = namedtuple("Forcing", "gF gS g0 gR VA VS GV GVS gLa gLs VLa VLs")

#: The root search's scratch (:func:`~.taylor._first_crossing`): a gap's series ``coef``, the
#: subdivision's rows ``wflat`` and stack ``stk``, each contact's first ``roots``, the
#: coordinates' tail sums ``colsum`` and the search ``order`` with its estimates ``est``.
RootWork = namedtuple("RootWork", "coef wflat stk roots colsum order est")


# -- the "expm" propagator's kernels (:mod:`gearmodal.integrate.kernels`) ---------------------
#: A contact state's propagators over the dyadic steps ``dt / 2^j``: ``PHI[j]``, the force
#: maps ``G0[j]``, ``G1[j]``, the constant part ``FS[j]``, and whether level ``j`` is there
#: (``have``).
Levels = namedtuple("Levels", "PHI G0 G1 FS have")

#: A contact state's first-order system ``x' = A x + Minv F + fcon``.
StateODE = namedtuple("StateODE", "A Minv fcon")

#: The gap rows ``W``, offsets ``off`` and each contact's sign ``sgn`` (+1 open, -1 closed).
GapRows = namedtuple("GapRows", "W off sgn")
