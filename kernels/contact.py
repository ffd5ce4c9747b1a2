"""Contact forces and torques, swept over the particles: each particle's pairs from the Verlet list
(`kernels/pair_contact.py`), its contacts with plane walls and tubes (`kernels/surface_contact.py`)
and with mesh walls (`kernels/mesh_contact.py`), and gravity.

Each pair is listed once, in the row of its owner (`kernels/broadphase.py`), and evaluated there,
the partner receiving the reaction. Particles are swept slab by slab (`kernels/geometry.py`): a
pair's partner lies in the owner's slab or in the next one. The slabs are grouped into blocks of consecutive slabs
(`block_count`: an even number of blocks, at most 16, each of two slabs or more; one block below
four slabs), so (`passes`)
1. pass 1: each block, one thread per block, sweeps its slabs but the last in order, each in index
   order (its pairs, walls and tubes), adding to the sums of that slab and the next, which the last
   kick-drift zeroed (`kernels/integrate.py`; and the contact counts, where the host reads them,
   here); when the step goes on, it integrates (`then`) each slab after the block's first as soon as
   it is swept: its sums are complete (each slab receives only from itself and the one before), and
   no pair left to evaluate reads it;
2. pass 2, once every block is through pass 1: each block's last slab likewise, then it integrates
   that slab and the next block's first one, now complete too;
so a slab's particles are mostly still in cache when they are swept after being added to as
partners, and integrated right after (2-5 % of a step of the peer bed at 10k and 50k against
sweeping even slabs, then odd ones, `benchmarks/README.md`; the blocks also share out better
among threads than eight or nine single slabs). No two threads then write the same particle, and
every sum is taken in the same order whatever the thread count (the blocks depend on the slab count
only): float64 runs are bit-reproducible without atomics. Each particle is read and written
about once per step, which is what the large beds, whose fields do not fit in cache, wait on. With
`atomic` (a GPU, where a slab per thread would leave it idle) every particle of a pass is a thread
of its own and the sums are atomic: the same forces, summed in an order that varies from run to run.
With heat the same evaluation adds the conduction (contact spot and gas lens) to the particles'
heat flows and to the heated surfaces' (`surf_rate`: on the CPU in rows of each block, added up in block
order after the passes, `kernels/surface_contact.py`; atomic on a GPU).

Mesh walls (`mesh_pass`): before the passes, a parallel loop of its own adds the mesh contacts of the
particles that list a triangle (a few: those at the apparatus' walls) to their sums, and clears the
contact counts (`diag`) that pass 1 would clear: the sweep that every particle goes through carries no
mesh code (on the CPU the same speed within this machine's noise, `benchmarks/README.md`; meant to keep
the few GPU threads with triangles from holding up the others' warps, not yet measured on a GPU).

Quiet partners (`kernels/pair_contact.py`): while no pair listed apart at the last build can have
closed, the pass evaluates only the partners that touched then; this changes no bit.

Gravity is added here: f_i = m_i g + sum of contact forces. `ovl[i]` receives the largest
overlap of particle i relative to the smaller radius of the pair, `ncontact[i]` its number of
contacts (coordination number), in the force passes that the host will read them after (`diag`
= 1: health checks, time series, snapshots; with contact timing in every pass): the division
per contact and the two stores per particle are 6 % of a step of the peer bed.
"""

from types import SimpleNamespace

import taichi as ti

from .contact_laws import make_contact_response
from .geometry import make_geometry, make_slabs
from .mesh_contact import make_mesh_contacts
from .ordered import in_order, make_sums, raise_max
from .pair_contact import make_pair_contacts
from .sizes import make_sizes
from .surface_contact import make_surface_contacts

# Loop iterations per worker in the slab loops. Taichi's CPU runtime (1.7) runs a parallel loop of fewer
# than about a thousand iterations on one thread and splits a longer one into one block of consecutive
# iterations per thread: a loop of SPREAD iterations per thread, of which the first of each block does
# the work of one worker, gives each thread one worker. The workers take the slabs of a pass one at a
# time from shared counters (`S.slab_next`): the host thread starts at once while the others are
# still waking up (tens of microseconds here), and a slab of more work holds up no one.
SPREAD = 1024
BLOCKS = 16  # the most blocks of slabs in a pass (`block_count`)


def block_count(n_slabs: int) -> int:
    """Blocks of consecutive slabs that the passes hand out (`passes`): an even number (two threads
    take as many), at most BLOCKS, each of at least two slabs; one below four slabs. Depends on the
    slab count only, never on the thread count (module docstring)."""
    if n_slabs < 4:
        return 1
    b = min(n_slabs // 2, BLOCKS)
    return b - b % 2


def make_force_kernel(grid, law: int, rolling: bool, planes: list[dict], tubes: list[dict], W: int, gravity, S,
                      track_contact_time: bool = False, one_material: tuple | None = None, heat: bool = False,
                      angle_bins: int = 0, fluid_layer: float = 0.0, pairs: bool = True,
                      radiation: bool = False, foil: bool = False, wall_foil: bool = False, cull: int = 0,
                      surface_reach: float = 0.0, grain_scale: float = 1.0, atomic: bool | None = None,
                      uniform: tuple[float, float] | None = None, quiet_margin: float = 0.0,
                      meshes: tuple[int, int, int, float, float, bool] | None = None):
    """Return a namespace of the kernel `forces(n, t, dt, conduct, diag)` (both passes), `passes(then)`,
    which makes the Taichi func of both passes that calls the Taichi func then(i, t, dt, drift, kick) on
    every particle whose sums are complete (`kernels/integrate.py` fuses the kick with them); `finish(i, t)` (the
    contact times, None without them) and `mark_near(i)` (below). With heat, `conduct` = m > 0 evaluates
    the conduction and books the heat of m steps (q[i] = m x the heat flow: heat.conduction_interval =
    m evaluates it every m-th step, an explicit Euler step of m dt), and `conduct` = 0 skips it (q[i] =
    0; the surfaces' heat flows of the last evaluation hold); S.conduct[None] tells the kick. `diag` = 1
    also fills ovl and ncontact (module docstring).
    `planes` and `tubes` (`tidem.walls.surfaces`) are compiled in as constants. `one_material`: where all particles
    are of one material, its material-pair parameter vector and its material-surface vector for each
    surface, and `uniform`: (radius, mass) where all have the same; the pair loop then takes them as
    constants of the kernel instead of loading them for every pair (12 % of the passes of the peer
    bed, whose products of constants the compiler then folds, `benchmarks/README.md`). `heat` adds conduction
    (kernels/heat.py) to the same loop, adding to q [W] and the heat flow into each surface with a
    temperature, surf_rate[s] [W] (into the bed > 0), and with `angle_bins` the heat flow from each tube
    by angle omega of the contact point from the top of the tube, tube_bin_rate[k, b] (omega =
    atan2(side, up), 0 = top, 180 deg = bottom). `fluid_layer` > 0 adds particle-fluid-particle
    conduction between neighbours closer than fluid_layer * min(r_i, r_j), touching or not, and between
    a surface with a temperature and a particle within fluid_layer * r_i of it that does not touch it
    (R* = r_i; a touching one conducts by Schluender's coefficient instead). `pairs = False`
    (contact.model = 'none') skips the neighbour list: gravity and walls only. `radiation` adds grey
    radiation from a heated surface to the particles touching it; with `foil`, a tube with
    tube_foil[k][0] > 0 (a heat flux) has the temperature of its foil in the angle bin of the contact
    point, tube_bin_T[k, b]; with `wall_foil`, a plane with plane_foil[s][0] > 0 has its foil's
    temperature plane_foil_T[s]. `cull` (bit s: surface s does not move) lets each particle skip the
    static surfaces farther than `surface_reach` (skin plus the conduction reach) at the last neighbour
    build, as marked in S.near by the Taichi func `mark_near(i)` (None without culling; the neighbour
    build runs it); a particle far from every wall and tube then costs no surface evaluation at all.
    `grain_scale` k > 1: every particle is a parcel of k^3 grains (one k per scene with heat) and
    conducts as those grains do (kernels/heat.py). `atomic`: atomic sums, one thread per particle
    (module docstring); None: on any architecture but the CPU. `quiet_margin` [m] > 0: skip quiet
    partners (module docstring) with that rounding margin; 0: evaluate every listed pair. `meshes`: (mesh
    count, candidates per particle, contact slots per particle, on-triangle tolerance [m], how far beyond
    its radius a particle lists triangles [m], whether any is heated) adds the
    mesh walls (`kernels/mesh_contact.py`); the namespace's `list_meshes(i)` is then their broad phase,
    which the neighbour build runs."""
    if atomic is None:
        atomic = not in_order()
    flat = atomic or not pairs  # one loop over the particles, no slabs
    n_slabs, _slab_of, succ, pred = make_slabs(grid)
    n_blocks = block_count(n_slabs)
    workers = max(1, ti.lang.impl.current_cfg().cpu_max_num_threads)
    min_image, _wrap, cell_coord, cell_id = make_geometry(grid)
    respond = make_contact_response(law, rolling)
    hysteretic = law == 2
    g = ti.Vector(list(gravity))
    zero3 = ti.Vector([0.0, 0.0, 0.0])
    p_one, s_one = one_material if one_material is not None else (None, None)
    radius_of, mass_of = make_sizes(S, uniform)
    add, raise_to = make_sums(atomic)
    pair = make_pair_contacts(S, respond, hysteretic, rolling, p_one, heat, fluid_layer, pairs and quiet_margin > 0.0,
                              grain_scale, min_image, radius_of, mass_of, add, raise_to) if pairs else None
    surf = make_surface_contacts(S, planes, tubes, W, respond, hysteretic, rolling, s_one, heat, fluid_layer, angle_bins,
                                 radiation, foil, wall_foil, cull, surface_reach, grain_scale, min_image, radius_of,
                                 0 if flat else BLOCKS)
    n_surf = surf.n_surf
    n_meshes = meshes[0] if meshes else 0
    mesh = None
    mesh_blocks = False
    if n_meshes:
        _n, per_particle, slots, on_tol, list_reach, heated = meshes
        mesh_blocks = heat and heated and not flat  # the heated meshes' flows in blocks (`mesh_pass`)
        mesh = make_mesh_contacts(S, law, rolling, n_surf, per_particle, slots, list_reach, on_tol, heat, fluid_layer,
                                  radiation, grain_scale, (cell_coord, cell_id), radius_of, mesh_blocks)

    @ti.func
    def note_contact_time(i, touching, t):
        """First time i touches anything and the first time after that it touches nothing."""
        if ti.static(track_contact_time):
            if touching > 0 and S.touch_start[i] < 0.0:
                S.touch_start[i] = t
            if touching == 0 and S.touch_start[i] >= 0.0 and S.touch_end[i] < 0.0:
                S.touch_end[i] = t

    @ti.func
    def clear(i):
        """Zero particle i's contact count and largest overlap before a force evaluation that fills
        them (the kick-drift zeroes the force, torque and heat flow)."""
        S.ovl[i] = 0.0
        S.ncontact[i] = 0

    @ti.func
    def visit(i, t, dt, conduct, diag, reach, blk):
        """Particle i's pairs (adding the reactions to the partners), walls, tubes and meshes, and
        gravity; its quiet partners only where their gap at the build is within `reach` (`quiet_reach`);
        its surfaces' heat flows booked in block blk's rows (slab passes; `kernels/surface_contact.py`)."""
        xi = S.x[i]
        ri = radius_of(i)
        mi = mass_of(i)
        wi = S.w[i]
        vi = S.v[i]
        mat_i = S.mat[i]
        force = mi * g
        torque = zero3
        worst = 0.0
        touching = 0
        heat_in = 0.0
        if ti.static(pairs):  # contact.model = 'none' compiles no pair loop
            force, torque, heat_in, worst, touching = pair.visit(i, xi, vi, wi, ri, mi, mat_i, dt, conduct, diag, reach,
                                                                 force, torque, heat_in, worst, touching)
        force, torque, heat_in, worst, touching = surf.visit(i, xi, vi, wi, ri, mi, mat_i, t, dt, conduct, diag,
                                                             force, torque, heat_in, worst, touching, blk)
        add(S.f, i, force)
        add(S.tq, i, torque)
        if ti.static(heat):
            add(S.q, i, conduct * heat_in)  # the heat of `conduct` steps, and none between evaluations
        if diag:
            raise_to(S.ovl, i, worst)
            add(S.ncontact, i, touching)

    @ti.func
    def mesh_particle(i, t, dt, conduct, diag, blk):
        """Particle i's diagnostics cleared (`diag`) and, where it lists a triangle, its mesh contacts added
        to its sums (plain stores: one thread per particle), heated meshes' flows in block blk's row."""
        if S.active[i]:
            if diag:
                clear(i)
            if S.mc_n[i] > 0:
                ri = radius_of(i)
                force, torque, heat_in, worst, touching = mesh.visit(
                    i, S.x[i], S.v[i], S.w[i], ri, mass_of(i), S.mat[i], t, dt, conduct, diag, zero3, zero3, 0.0, 0.0, 0,
                    blk)
                S.f[i] = S.f[i] + force
                S.tq[i] = S.tq[i] + torque
                if ti.static(heat):
                    S.q[i] = S.q[i] + conduct * heat_in
                if diag:
                    S.ovl[i] = worst
                    S.ncontact[i] = touching

    @ti.func
    def mesh_pass(n, t, dt, conduct, diag):
        """Before the pair passes, a loop of its own over the particles (`mesh_particle`); kept out of the pair
        sweep, the mesh code costs a particle that lists no triangle two loads (module docstring). With heated
        meshes on the CPU in BLOCKS blocks of consecutive particles, each in index order: their heat flows are
        then summed in the same order on any thread count (`kernels/surface_contact.py`; the blocks cost
        hopper_discharge, had it heated meshes, 16 % of its force pass against one particle a task)."""
        if ti.static(not mesh_blocks):
            for i in range(n):
                mesh_particle(i, t, dt, conduct, diag, 0)
        else:
            ti.loop_config(block_dim=1)  # a block per task: the CPU's default grain would give one thread all 16
            for blk in range(BLOCKS):
                for i in range(blk * n // BLOCKS, (blk + 1) * n // BLOCKS):
                    mesh_particle(i, t, dt, conduct, diag, blk)

    @ti.func
    def quiet_reach():
        """How far apart two particles listed at the last neighbour build may now have come closer:
        twice the largest displacement since then (S.max_disp holds it squared, from the last
        kick-drift; 0 after a build), plus `quiet_margin` for rounding. A partner whose gap
        was wider cannot touch yet."""
        return 2.0 * ti.sqrt(S.max_disp[None]) + quiet_margin

    @ti.func
    def block_start(b):
        """The first slab of block b (block n_blocks: n_slabs)."""
        return b * n_slabs // n_blocks

    @ti.func
    def clear_slab(s):
        for p in range(S.slab_start[s], S.slab_start[s + 1]):
            clear(S.slab_list[p])

    @ti.func
    def sweep_slab(s, t, dt, conduct, diag, reach, blk):
        for p in range(S.slab_start[s], S.slab_start[s + 1]):
            visit(S.slab_list[p], t, dt, conduct, diag, reach, blk)

    @ti.func
    def start_pass(conduct):
        """Before the passes: the conduction of this step for the kick, and with it the surfaces' heat
        flows zeroed (else those of the last evaluation hold)."""
        if ti.static(heat):
            S.conduct[None] = conduct
            if conduct:
                surf.clear_flows()  # (serial loops: a few items, no thread-pool round trip)

    def passes(then=None):
        """Both passes (module docstring) as a Taichi func passes(n, t, dt, conduct, diag, drift, kick)
        that calls the Taichi func then(i, t, dt, drift, kick) on every particle once its sums are
        complete and keeps the largest value it returns in S.max_disp[None] (the squared displacements
        of the kick-drifts): one atomic per worker, not one per particle. One parallel loop: each
        worker takes blocks from a shared counter (S.slab_next[0]) while any are left, waits until
        every block is through pass 1 (S.slab_next[1] counts them), then takes blocks' last slabs
        (S.slab_next[2]). A worker waits only for blocks that another one took and is sweeping, so the
        loop finishes on any number of threads, one included; it saves the start of a second parallel
        loop (about 50 us on two threads, `benchmarks/README.md`). With `flat`: two loops over the
        particles."""
        kicks = then is not None

        @ti.func
        def integrate_slab(s, t, dt, drift, kick):
            largest = 0.0
            for p in range(S.slab_start[s], S.slab_start[s + 1]):
                largest = ti.max(largest, then(S.slab_list[p], t, dt, drift, kick))
            return largest

        @ti.func
        def both(n, t, dt, conduct, diag, drift, kick):
            if ti.static(track_contact_time):
                diag = 1  # the contact times need the count in every pass
            reach = quiet_reach()
            if ti.static(kicks):
                S.max_disp[None] = 0.0  # the kick-drifts' displacements follow
            start_pass(conduct)
            if ti.static(n_meshes):
                mesh_pass(n, t, dt, conduct, diag)
            if ti.static(flat):
                if ti.static(not n_meshes):  # (else the mesh pass has cleared them)
                    if diag:
                        for i in range(n):
                            if S.active[i]:
                                clear(i)
                for i in range(n):
                    if S.active[i]:
                        visit(i, t, dt, conduct, diag, reach, 0)
                if ti.static(kicks):
                    for i in range(n):
                        if S.active[i]:
                            raise_max(S.max_disp, then(i, t, dt, drift, kick))
            else:
                for c in ti.static(range(3)):
                    S.slab_next[c] = 0
                for e in range(workers * SPREAD):
                    if e % SPREAD == 0:
                        largest = 0.0
                        while True:  # pass 1
                            b = ti.atomic_add(S.slab_next[0], 1)
                            if b >= n_blocks:
                                break
                            lo, hi = block_start(b), block_start(b + 1)
                            if ti.static(not n_meshes):  # (else the mesh pass has cleared them)
                                if diag:
                                    for s in range(lo, hi):
                                        clear_slab(s)
                            for s in range(lo, hi - 1):
                                sweep_slab(s, t, dt, conduct, diag, reach, b)
                                if ti.static(kicks):
                                    if s > lo or pred(s) < 0:  # complete: its predecessor is swept
                                        largest = ti.max(largest, integrate_slab(s, t, dt, drift, kick))
                            ti.atomic_add(S.slab_next[1], 1)
                        while ti.atomic_add(S.slab_next[1], 0) < n_blocks:  # pass 2 adds to the blocks' first slabs
                            pass
                        while True:  # pass 2
                            b = ti.atomic_add(S.slab_next[2], 1)
                            if b >= n_blocks:
                                break
                            last = block_start(b + 1) - 1
                            sweep_slab(last, t, dt, conduct, diag, reach, b)
                            if ti.static(kicks):
                                largest = ti.max(largest, integrate_slab(last, t, dt, drift, kick))
                                after = succ(last)  # the next block's first slab
                                if after >= 0 and after != last:
                                    largest = ti.max(largest, integrate_slab(after, t, dt, drift, kick))
                        if ti.static(kicks):
                            ti.atomic_max(S.max_disp[None], largest)
                if ti.static(heat):
                    if conduct:
                        surf.sum_blocks()

        return both

    forces_only = passes()

    @ti.kernel
    def forces(n: ti.i32, t: float, dt: float, conduct: ti.i32, diag: ti.i32):
        forces_only(n, t, dt, conduct, diag, 0, 0)

    @ti.func
    def finish(i, t):
        """The contact times of particle i, from its complete contact count."""
        note_contact_time(i, S.ncontact[i], t)

    return SimpleNamespace(forces=forces, passes=passes,
                           finish=finish if track_contact_time else None, mark_near=surf.mark_near,
                           list_meshes=mesh.list_candidates if mesh is not None else None)
