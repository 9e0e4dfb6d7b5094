"""The push that measures the soil relaxation's convergence, shared by
tools/plot_soil_convergence.py and tools/soil_convergence_sweep.py (and the
same as push() in tests/core/soil_converge_test.cpp): a blade of width_m
cutting 4 cm into a 20 cm layer of dry sand (repose 34 degrees) on square
cells of cell_m, pushed travel_m along +Z from z = 0.4 m at speed_m_per_s
(1 kHz steps), then held still for hold_s, with the relaxation's work cap at
cap neighbour visits a step (None: the library's default,
soil.max_pair_checks_per_step; 1e9 lifts it: the converged answer). The grid is (width + 1.6) / cell by (travel + 1.4) / cell
cells. With yaw_deg, the blade turned that far about the vertical and
pushed along its normal (sin yaw, 0, cos yaw) across the middle of a square
grid of (width + travel + 1.6) / cell cells a side."""

DEPTH, LAYER, Z0 = 0.04, 0.2, 0.4


def grid_shape(width_m, cell_m, travel_m):
    """(cols, rows) of the push's grid."""
    return int(round((width_m + 1.6) / cell_m)), int(round((travel_m + 1.4) / cell_m))


def push_x(width_m, cell_m):
    """X of the blade's centre (m): the middle of the grid's width."""
    return 0.5 * grid_shape(width_m, cell_m, 0.0)[0] * cell_m


def push(terracut, np, width_m, cell_m, speed_m_per_s, cap, travel_m=0.8, hold_s=0.2, yaw_deg=0.0, settle=None):
    """A dict: heights (rows, cols) after the hold; ahead (m^3 of soil above
    the layer ahead of the edge within the blade's width) and peak (its
    highest point above the layer, m); capped (steps the cap stopped) and
    work (neighbour visits in all), over the push's and the hold's steps.
    settle: the soil's settle (patches, passes or fans; None: the default)."""
    if yaw_deg != 0.0:
        return push_at_yaw(terracut, np, width_m, cell_m, speed_m_per_s, cap, travel_m, hold_s, yaw_deg, settle)
    cols, rows = grid_shape(width_m, cell_m, travel_m)
    x = push_x(width_m, cell_m)
    soil = soil_params(cap, settle)
    scenario = terracut.Scenario.from_dict({
        "name": "converge",
        "terrain": {"generator": "plane", "resolution": [cols, rows],
                    "size_m": [cols * cell_m, rows * cell_m], "origin_m": [0, 0, 0],
                    "full_scale_m": 0.6, "plane": {"height_m": LAYER}},
        "soil": soil,
        "blade": {"length_m": width_m},
        "cuts": [{"name": "push", "keyframes": [
            {"t_s": 0.0, "position_m": [x, LAYER - DEPTH, Z0], "rotation_deg": [0, 0, 0]},
            {"t_s": travel_m / speed_m_per_s, "position_m": [x, LAYER - DEPTH, Z0 + travel_m],
             "rotation_deg": [0, 0, 0]}]}],
    })
    sim = terracut.Simulation(scenario)
    steps = int(round(travel_m / speed_m_per_s * 1000.0))
    s = np.minimum(np.arange(steps + int(round(hold_s * 1000.0)) + 1) / steps, 1.0)
    poses = np.zeros((len(s), 7))
    poses[:, 0] = x
    poses[:, 1] = LAYER - DEPTH
    poses[:, 2] = Z0 + travel_m * s
    poses[:, 3] = 1.0
    columns = sim.step(poses)
    h = np.array(sim.heights, dtype=np.float64)
    z = (np.arange(rows) + 0.5) * cell_m
    xs = (np.arange(cols) + 0.5) * cell_m
    ahead = (z[:, None] > Z0 + travel_m) & (np.abs(xs[None, :] - x) < 0.5 * width_m)
    above = np.where(ahead, np.maximum(h - LAYER, 0.0), 0.0)
    return {"heights": h, "ahead": float(above.sum() * cell_m * cell_m), "peak": float(above.max()),
            "capped": int(columns["soil_capped"].sum()), "work": int(columns["soil_work"].sum())}


def soil_params(cap, settle=None):
    """The pushes' soil: flow, dry sand, at the work cap (None: the
    default), settled as `settle` says (None: the default)."""
    soil = {"model": "flow", "repose_deg": 34}
    if cap is not None:
        soil["max_pair_checks_per_step"] = int(cap)
    if settle is not None:
        soil["settle"] = settle
    return soil


def push_at_yaw(terracut, np, width_m, cell_m, speed_m_per_s, cap, travel_m, hold_s, yaw_deg, settle=None):
    """push() with the blade turned yaw_deg about the vertical (see the
    module's text); the same dict."""
    n = int(round((width_m + travel_m + 1.6) / cell_m))
    side = n * cell_m
    yaw = np.radians(yaw_deg)
    tx, tz = np.sin(yaw), np.cos(yaw)
    c = 0.5 * side
    start = (c - 0.5 * travel_m * tx, c - 0.5 * travel_m * tz)
    end = (c + 0.5 * travel_m * tx, c + 0.5 * travel_m * tz)
    scenario = terracut.Scenario.from_dict({
        "name": "converge",
        "terrain": {"generator": "plane", "resolution": [n, n], "size_m": [side, side], "origin_m": [0, 0, 0],
                    "full_scale_m": 0.6, "plane": {"height_m": LAYER}},
        "soil": soil_params(cap, settle),
        "blade": {"length_m": width_m},
        "cuts": [{"name": "push", "keyframes": [
            {"t_s": 0.0, "position_m": [start[0], LAYER - DEPTH, start[1]], "rotation_deg": [0, yaw_deg, 0]},
            {"t_s": travel_m / speed_m_per_s, "position_m": [end[0], LAYER - DEPTH, end[1]],
             "rotation_deg": [0, yaw_deg, 0]}]}],
    })
    sim = terracut.Simulation(scenario)
    steps = int(round(travel_m / speed_m_per_s * 1000.0))
    s = np.minimum(np.arange(steps + int(round(hold_s * 1000.0)) + 1) / steps, 1.0)
    poses = np.zeros((len(s), 7))
    poses[:, 0] = start[0] + travel_m * tx * s
    poses[:, 1] = LAYER - DEPTH
    poses[:, 2] = start[1] + travel_m * tz * s
    poses[:, 3] = np.cos(0.5 * yaw)
    poses[:, 5] = np.sin(0.5 * yaw)
    columns = sim.step(poses)
    h = np.array(sim.heights, dtype=np.float64)
    centres = (np.arange(n) + 0.5) * cell_m
    dx = centres[None, :] - end[0]
    dz = centres[:, None] - end[1]
    ahead = (dx * tx + dz * tz > 0.0) & (np.abs(dx * tz - dz * tx) < 0.5 * width_m)
    above = np.where(ahead, np.maximum(h - LAYER, 0.0), 0.0)
    return {"heights": h, "ahead": float(above.sum() * cell_m * cell_m), "peak": float(above.max()),
            "capped": int(columns["soil_capped"].sum()), "work": int(columns["soil_work"].sum())}
