"""world/: the occupancy grid, inflation, the planner, scan updates, leg checks and standoffs."""

from __future__ import annotations

import heapq
import math
import random

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from shadowhound.robot.sim.scene import DEFAULT_WORLD, World, WorldObject
from shadowhound.robot.sim.sensors import cast_scan, scene_belief, scene_grid
from shadowhound.state import Pose2D, Scan
from shadowhound.world import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    Belief,
    Cell,
    GridError,
    KnownObject,
    OccupancyGrid,
    PlanError,
    apply_scan,
    check_leg,
    inflate,
    line_is_clear,
    plan_path,
    standoff_point,
)

SQRT2 = math.sqrt(2)


# -- the grid ---------------------------------------------------------------------------


def test_grid_round_trips_the_nav_msgs_layout():
    grid = OccupancyGrid(3, 2, 0.1, Pose2D(-1.0, 2.0, 0.0))
    grid.set(Cell(0, 0), FREE)
    grid.set(Cell(2, 1), OCCUPIED)
    grid.set(Cell(1, 1), 42)
    msg = grid.to_msg()
    assert msg["data"] == [0, -1, -1, -1, 42, 100]  # row-major, row 0 first, -1 unknown
    assert msg["info"]["origin"]["position"]["x"] == -1.0
    back = OccupancyGrid.from_msg(msg)
    assert back.cells == grid.cells and back.resolution == 0.1 and back.origin == grid.origin
    # The cell holding a point: columns along x from the origin's corner, rows along y.
    assert grid.cell_of(-0.75, 2.15) == Cell(2, 1)
    assert grid.center_of(Cell(2, 1)) == pytest.approx((-0.75, 2.15))


def test_a_rotated_origin_maps_points_through_its_yaw():
    grid = OccupancyGrid(10, 10, 0.5, Pose2D(0.0, 0.0, math.pi / 2))
    # Columns run along +y of the map, rows along -x.
    assert grid.cell_of(0.2, 1.7) == Cell(3, 0) or grid.cell_of(-0.2, 1.7) == Cell(3, 0)
    assert grid.cell_of(-0.2, 1.7) == Cell(3, 0)
    x, y = grid.center_of(Cell(3, 0))
    assert (x, y) == pytest.approx((-0.25, 1.75))
    assert OccupancyGrid.from_msg(grid.to_msg()).origin.yaw == pytest.approx(math.pi / 2)


@pytest.mark.parametrize(
    "msg, words",
    [
        ({"info": {}}, "missing or bad"),
        (
            {
                "info": {
                    "width": 2,
                    "height": 2,
                    "resolution": 0.05,
                    "origin": {"position": {"x": 0, "y": 0}},
                },
                "data": [0, 0, 0],
            },
            "expected",
        ),
        (
            {
                "info": {
                    "width": 0,
                    "height": 2,
                    "resolution": 0.05,
                    "origin": {"position": {"x": 0, "y": 0}},
                },
                "data": [],
            },
            "positive",
        ),
        (
            {
                "info": {
                    "width": 1,
                    "height": 1,
                    "resolution": -1,
                    "origin": {"position": {"x": 0, "y": 0}},
                },
                "data": [0],
            },
            "resolution",
        ),
    ],
)
def test_a_malformed_map_is_refused_with_a_reason(msg, words):
    with pytest.raises(GridError, match=words):
        OccupancyGrid.from_msg(msg)


def test_values_outside_the_occupancy_range_read_as_unknown():
    grid = OccupancyGrid.from_msg(
        {
            "info": {
                "width": 3,
                "height": 1,
                "resolution": 1.0,
                "origin": {"position": {"x": 0, "y": 0}},
            },
            "data": [-5, 101, 7],
        }
    )
    assert grid.int8_data() == [-1, -1, 7]


def test_grid_from_the_scene_marks_objects_walls_and_free_floor():
    grid = scene_grid(DEFAULT_WORLD)
    assert grid.resolution == 0.05
    for obj in DEFAULT_WORLD.objects:
        assert grid.value_at(obj.x, obj.y) == OCCUPIED, obj.name
        # Every cell the disc touches is occupied: just inside its rim, too.
        assert grid.value_at(obj.x + obj.radius * 0.99, obj.y) == OCCUPIED, obj.name
    assert grid.value_at(0.0, 0.0) == FREE
    assert grid.value_at(6.05, 0.0) == OCCUPIED and grid.value_at(0.0, -6.05) == OCCUPIED
    assert grid.value_at(5.9, 0.0) == FREE
    assert grid.count("unknown") == 0


# -- inflation --------------------------------------------------------------------------


def _brute_inflation(grid: OccupancyGrid, radius: float) -> set[Cell]:
    """Cells any point of which lies within `radius` of an occupied cell's square."""
    occupied = [
        Cell(c, r)
        for r in range(grid.height)
        for c in range(grid.width)
        if grid.is_occupied(Cell(c, r))
    ]
    out = set()
    for r in range(grid.height):
        for c in range(grid.width):
            for o in occupied:
                gap_c = max(abs(o.col - c) - 1, 0)
                gap_r = max(abs(o.row - r) - 1, 0)
                if o == Cell(c, r) or math.hypot(gap_c, gap_r) < radius / grid.resolution:
                    out.add(Cell(c, r))
                    break
    return out


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), radius=st.floats(0.0, 0.4))
def test_inflation_blocks_exactly_the_cells_within_the_radius_of_an_obstacle(seed, radius):
    rng = random.Random(seed)
    grid = OccupancyGrid.empty(0, 1.5, 0, 1.2, 0.05, value=FREE)
    for _ in range(rng.randint(0, 6)):
        grid.set(Cell(rng.randrange(grid.width), rng.randrange(grid.height)), OCCUPIED)
    for _ in range(rng.randint(0, 2)):  # walls and blocks: runs stacked over many rows
        x, y = rng.uniform(-0.2, 1.5), rng.uniform(-0.2, 1.2)
        grid.fill_rect(x, x + rng.uniform(0.01, 0.6), y, y + rng.uniform(0.01, 1.0), OCCUPIED)
    inflated = inflate(grid, radius)
    got = {
        Cell(c, r)
        for r in range(grid.height)
        for c in range(grid.width)
        if inflated.is_blocked(Cell(c, r))
    }
    assert got == _brute_inflation(grid, radius)


def test_unknown_space_is_blocked_unless_allowed():
    grid = OccupancyGrid.empty(0, 1, 0, 1, 0.1, value=FREE)
    grid.set(Cell(5, 5), UNKNOWN)
    assert inflate(grid, 0.0).is_blocked(Cell(5, 5))
    assert not inflate(grid, 0.0, unknown_is_free=True).is_blocked(Cell(5, 5))
    assert inflate(grid, 0.0).is_blocked(Cell(-1, 0))  # off the map


# -- the planner ------------------------------------------------------------------------


def _reference_length(inflated, start: Cell, goal: Cell) -> float:
    """Dijkstra over 8-connected cells, no corner cutting: the optimal grid path (cells)."""
    dist = {start: 0.0}
    heap = [(0.0, start.col, start.row)]
    while heap:
        d, c, r = heapq.heappop(heap)
        if (c, r) == (goal.col, goal.row):
            return d
        if d > dist.get(Cell(c, r), math.inf):
            continue
        for dc in (-1, 0, 1):
            for dr in (-1, 0, 1):
                if not (dc or dr):
                    continue
                n = Cell(c + dc, r + dr)
                if inflated.is_blocked(n):
                    continue
                if (
                    dc
                    and dr
                    and (
                        inflated.is_blocked(Cell(c + dc, r)) or inflated.is_blocked(Cell(c, r + dr))
                    )
                ):
                    continue
                nd = d + (SQRT2 if dc and dr else 1.0)
                if nd < dist.get(n, math.inf):
                    dist[n] = nd
                    heapq.heappush(heap, (nd, n.col, n.row))
    return math.inf


def _random_grid(seed: int) -> OccupancyGrid:
    rng = random.Random(seed)
    grid = OccupancyGrid.empty(0, 4, 0, 3, 0.05, value=FREE)
    for _ in range(rng.randint(0, 12)):
        grid.fill_circle(rng.uniform(0, 4), rng.uniform(0, 3), rng.uniform(0.05, 0.4), OCCUPIED)
    for _ in range(rng.randint(0, 3)):  # walls with gaps: corridors and doorways
        x = rng.uniform(0.5, 3.5)
        gap = rng.uniform(0, 2.5)
        grid.fill_rect(x, x + 0.1, 0, gap, OCCUPIED)
        grid.fill_rect(x, x + 0.1, gap + rng.uniform(0.3, 1.2), 3, OCCUPIED)
    return grid


def _free_cell(inflated, rng: random.Random) -> Cell | None:
    grid = inflated.grid
    for _ in range(200):
        cell = Cell(rng.randrange(grid.width), rng.randrange(grid.height))
        if not inflated.is_blocked(cell):
            return cell
    return None


def _assert_path_is_clear(inflated, path) -> None:
    for a, b in zip(path.waypoints, path.waypoints[1:], strict=False):
        assert line_is_clear(inflated, a, b), (a, b)
        # Independent of the supercover walk: sample each leg densely.
        n = max(1, math.ceil(math.dist(a, b) / (inflated.grid.resolution / 8)))
        for i in range(n + 1):
            x = a[0] + (b[0] - a[0]) * i / n
            y = a[1] + (b[1] - a[1]) * i / n
            assert inflated.is_free_at(x, y), (x, y)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 100_000), radius=st.sampled_from([0.0, 0.1, 0.2, 0.35]))
def test_paths_are_near_optimal_and_never_cross_an_inflated_obstacle(seed, radius):
    rng = random.Random(seed)
    inflated = inflate(_random_grid(seed), radius)
    start, goal = _free_cell(inflated, rng), _free_cell(inflated, rng)
    if start is None or goal is None:
        return
    grid = inflated.grid
    ref = _reference_length(inflated, start, goal)
    a, b = grid.center_of(start), grid.center_of(goal)
    if ref == math.inf:
        with pytest.raises(PlanError, match="no collision-free path"):
            plan_path(inflated, a, b)
        return
    path = plan_path(inflated, a, b)
    assert path.waypoints[0] == a and path.waypoints[-1] == b
    # The search is optimal on the 8-connected grid; the shortcuts only shorten it.
    assert path.grid_length == pytest.approx(ref * grid.resolution, abs=1e-6)
    assert math.dist(a, b) - 1e-9 <= path.length <= path.grid_length + 1e-9
    assert path.length <= 1.15 * ref * grid.resolution + 1e-9
    _assert_path_is_clear(inflated, path)


def test_a_path_goes_around_the_red_ball_where_a_straight_line_would_hit_it():
    belief = scene_belief(DEFAULT_WORLD, 0.35)
    path = plan_path(belief.inflated, (0.0, 0.0), (4.0, 0.0))
    assert len(path.waypoints) >= 3  # not straight through the ball
    assert 4.0 < path.length < 4.0 * 1.15
    _assert_path_is_clear(belief.inflated, path)
    ball = DEFAULT_WORLD.find("red ball")
    for a, b in zip(path.waypoints, path.waypoints[1:], strict=False):
        assert _segment_distance((ball.x, ball.y), a, b) >= ball.radius + 0.35


def _segment_distance(p, a, b) -> float:
    ax, ay = a
    bx, by = b
    dx, dy = bx - ax, by - ay
    t = (
        0.0
        if not (dx or dy)
        else max(0.0, min(1.0, ((p[0] - ax) * dx + (p[1] - ay) * dy) / (dx * dx + dy * dy)))
    )
    return math.hypot(ax + t * dx - p[0], ay + t * dy - p[1])


def test_a_blocked_goal_or_a_walled_off_goal_is_refused_with_the_reason():
    belief = scene_belief(DEFAULT_WORLD, 0.35)
    with pytest.raises(PlanError, match="inside an obstacle"):
        plan_path(belief.inflated, (0.0, 0.0), (3.0, 0.0))
    with pytest.raises(PlanError, match="closer than 0.35 m"):
        plan_path(belief.inflated, (0.0, 0.0), (3.0, 0.4))
    with pytest.raises(PlanError, match="outside the map"):
        plan_path(belief.inflated, (0.0, 0.0), (30.0, 0.0))
    room = World(objects=(), bounds=(0.0, 4.0, 0.0, 2.0))
    walled = scene_grid(room)
    walled.fill_rect(2.0, 2.1, 0.0, 2.0, OCCUPIED)
    with pytest.raises(PlanError, match="no collision-free path"):
        plan_path(inflate(walled, 0.35), (1.0, 1.0), (3.0, 1.0))


def test_points_that_are_not_finite_or_far_away_are_refused_not_crashed_on():
    """Odometry that lies (issue 21): a NaN goal crashed the governor inside cell_of."""
    from shadowhound.world import plan_route

    belief = scene_belief(DEFAULT_WORLD, 0.35)
    with pytest.raises(GridError, match=r"not finite \(x=nan\)"):
        belief.grid.cell_of(math.nan, 0.0)
    assert not belief.grid.contains(belief.grid.cell_of(1e308, -1e308))  # no overflow
    for start, goal, said in [
        ((0.0, 0.0), (math.nan, 1.0), r"the goal is not a point on the map: .*\(x=nan\)"),
        ((0.0, math.inf), (1.0, 1.0), r"the start is not a point on the map: .*\(y=inf\)"),
        ((0.0, 0.0), (1e308, 0.0), "outside the map"),
        ((-1e308, 0.0), (1.0, 0.0), "the start .* is outside the map"),
    ]:
        with pytest.raises(PlanError, match=said):
            plan_path(belief.inflated, start, goal)
        with pytest.raises(PlanError, match=said):
            plan_route(belief, start, goal)
    ball = next(o for o in belief.objects if o.name == "red ball")
    with pytest.raises(PlanError, match="not finite"):
        standoff_point(belief, (math.nan, 0.0), ball)


def test_a_start_inside_a_clearance_zone_first_backs_out_of_it():
    belief = scene_belief(DEFAULT_WORLD, 0.35)
    # Where the body stopped when it walked into the red ball.
    path = plan_path(belief.inflated, (2.45, 0.0), (0.0, 0.0))
    assert path.escaped and path.waypoints[0] == (2.45, 0.0)
    assert path.waypoints[-1] == (0.0, 0.0)


# -- scans ------------------------------------------------------------------------------


def test_a_scan_of_the_scene_rebuilds_what_the_robot_can_see():
    world = DEFAULT_WORLD
    pose = Pose2D(0.0, 0.0, 0.3)
    scan = cast_scan(world, pose)
    assert len(scan.ranges) == 360
    ahead = scan.ranges[180]  # beam 180 points along the robot's heading
    truth = scene_grid(world)
    grid = OccupancyGrid.empty(-6.1, 6.1, -6.1, 6.1, 0.05)
    hits = apply_scan(grid, scan)
    assert hits == sum(1 for r in scan.ranges if scan.is_hit(r))
    assert math.isfinite(ahead)
    # Every hit cell agrees with the scene (a hit lies on a surface, within a cell of it).
    for i, r in enumerate(scan.ranges):
        if scan.is_hit(r):
            a = scan.beam_angle(i)
            x, y = pose.x + (r + 0.0125) * math.cos(a), pose.y + (r + 0.0125) * math.sin(a)
            assert grid.value_at(x, y) == OCCUPIED
            back = (x - 0.06 * math.cos(a), y - 0.06 * math.sin(a))
            assert truth.value_at(*back) in (FREE, OCCUPIED)
    # Free space the scan claims is free in truth too: no free cell's centre lies inside an
    # object or beyond a wall (the truth grid also marks cells an object merely touches).
    # Between two beams the outline is a chord of a round object: 2 cm of slack covers it.
    wrong = []
    for r_ in range(grid.height):
        for c in range(grid.width):
            if grid.value(Cell(c, r_)) == FREE:
                x, y = grid.center_of(Cell(c, r_))
                if not world.contains(x, y) or any(
                    math.hypot(o.x - x, o.y - y) < o.radius - 0.02 for o in world.objects
                ):
                    wrong.append((x, y))
    assert wrong == []
    assert grid.value_at(0.5, 0.0) == FREE and grid.value_at(1.0, 1.0) == FREE
    # Behind the red ball, seen from here, is still unknown.
    assert grid.value_at(3.5, 0.0) == UNKNOWN


def test_a_scan_clears_an_obstacle_that_moved_away_but_not_one_between_beams():
    grid = OccupancyGrid.empty(-3, 3, -3, 3, 0.05, value=UNKNOWN)
    grid.set(grid.cell_of(1.0, 0.0), OCCUPIED)  # seen before, now gone: a beam runs through
    # Eight beams only: a cell far out between two of them is not crossed by either.
    between = (2.0 * math.cos(math.pi / 8), 2.0 * math.sin(math.pi / 8))
    grid.set(grid.cell_of(*between), OCCUPIED)
    scan = Scan(tuple([2.5] * 8), -math.pi, 2 * math.pi / 8, 0.1, 8.0, Pose2D())
    apply_scan(grid, scan)
    assert grid.value_at(1.0, 0.0) == FREE
    assert grid.value_at(*between) == OCCUPIED
    assert grid.value_at(2.5, 0.0) == OCCUPIED


def test_misses_and_errors_claim_nothing_past_what_they_can():
    grid = OccupancyGrid.empty(-10, 10, -10, 10, 0.05, value=UNKNOWN)
    ranges = [math.inf] * 360
    ranges[180] = math.nan  # a broken beam straight ahead
    apply_scan(grid, Scan(tuple(ranges), pose=Pose2D()))
    assert grid.value_at(7.0, 3.0) == FREE  # inf: free to the sensor's reach (8 m)
    assert grid.value_at(9.0, 0.0) == UNKNOWN
    assert grid.count("occupied") == 0


# -- the straight-leg check and standoffs -----------------------------------------------


def test_a_leg_through_the_red_ball_names_it_and_the_distance():
    belief = scene_belief(DEFAULT_WORLD, 0.35)
    verdict = check_leg(belief, (0.0, 0.0), (4.0, 0.0))
    assert not verdict.clear and verdict.obstacle == "the red ball"
    # The body touches the ball when its centre is 0.2 + 0.35 m short of the ball's centre.
    assert 2.45 - 0.15 <= verdict.distance <= 2.45
    assert verdict.message() == f"the red ball is in the way at {verdict.distance:.1f} m"
    assert check_leg(belief, (0.0, 0.0), (2.0, 0.0)).clear
    wall = check_leg(belief, (0.0, 0.0), (0.0, 7.0))
    assert not wall.clear and wall.obstacle == "the wall" and 5.45 <= wall.distance <= 5.65


def test_an_unnamed_obstacle_and_unmapped_space_are_said_as_such():
    grid = OccupancyGrid.empty(-1, 5, -2, 2, 0.05, value=FREE)
    grid.fill_circle(2.0, 0.0, 0.2, OCCUPIED)
    grid.fill_rect(4.0, 5.0, -2, 2, 0)
    grid.fill_rect(4.5, 5.0, -2, 2, 0)
    belief = Belief(grid, (KnownObject("crate", 2.0, 1.5, 0.2),), 0.35)
    assert check_leg(belief, (0.0, 0.0), (3.0, 0.0)).obstacle == "an obstacle"
    grid.fill_rect(3.0, 5.0, -2, 2, UNKNOWN)
    belief.changed()
    verdict = check_leg(belief, (0.0, 1.0), (4.0, 1.0))
    assert verdict.obstacle == "unmapped space" and "mapped free space" in verdict.message()


def test_a_robot_pressed_against_an_obstacle_may_walk_away_but_not_further_in():
    belief = scene_belief(DEFAULT_WORLD, 0.35)
    assert check_leg(belief, (2.45, 0.0), (0.5, 0.0)).clear
    verdict = check_leg(belief, (2.45, 0.0), (3.5, 0.0))
    assert not verdict.clear and verdict.obstacle == "the red ball"


def test_a_standoff_is_free_reachable_and_faces_the_object():
    belief = scene_belief(DEFAULT_WORLD, 0.35)
    for obj in belief.objects:
        spot = standoff_point(belief, (0.0, 0.0), obj)
        d = math.hypot(obj.x - spot.pose.x, obj.y - spot.pose.y)
        gap = 1.05 if obj.name == "person" else 0.6  # a person: at least a metre, 5 cm spare
        assert d == pytest.approx(obj.radius + gap, abs=1e-6), obj.name
        assert belief.inflated.is_free_at(spot.pose.x, spot.pose.y)
        bearing = math.atan2(obj.y - spot.pose.y, obj.x - spot.pose.x)
        assert spot.pose.yaw == pytest.approx(bearing)
        assert spot.path.waypoints[-1] == pytest.approx((spot.pose.x, spot.pose.y))
        _assert_path_is_clear(belief.inflated, spot.path)


def test_a_person_is_given_at_least_a_metre_whatever_the_standoff_asked():
    belief = scene_belief(DEFAULT_WORLD, 0.35)
    for name, gap, expected in (
        ("person", 0.6, 1.05),
        ("the tall man", 0.6, 1.05),
        ("person", 1.4, 1.4),
        ("chairperson desk", 0.6, 0.6),
    ):
        obj = KnownObject(name, 0.0, -3.0, 0.25)
        spot = standoff_point(belief, (0.0, 0.0), obj, gap)
        d = math.hypot(obj.x - spot.pose.x, obj.y - spot.pose.y)
        assert d == pytest.approx(obj.radius + expected, abs=1e-6), name


def test_an_object_with_no_room_around_it_has_no_standoff():
    world = World(objects=(WorldObject("box", 0.8, 0.8, 0.3),), bounds=(0.0, 1.6, 0.0, 1.6))
    belief = scene_belief(world, 0.35)
    with pytest.raises(PlanError, match="no reachable place 0.6 m from the box"):
        standoff_point(belief, (0.4, 0.4), belief.objects[0])


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 100_000))
@example(seed=65658)  # an object's edge between the last beam and the first (the wrap)
def test_a_scan_never_marks_free_what_is_inside_an_object_or_a_wall(seed):
    rng = random.Random(seed)
    objects = tuple(
        WorldObject(f"thing {i}", rng.uniform(-4, 4), rng.uniform(-4, 4), rng.uniform(0.1, 0.8))
        for i in range(rng.randint(0, 8))
    )
    world = World(objects=objects, bounds=(-4.5, 4.5, -3.0, 3.0))
    while True:
        x, y = rng.uniform(-4.3, 4.3), rng.uniform(-2.8, 2.8)
        if all(math.hypot(o.x - x, o.y - y) > o.radius + 0.1 for o in objects):
            break
    scan = cast_scan(world, Pose2D(x, y, rng.uniform(-math.pi, math.pi)))
    grid = OccupancyGrid.empty(-5, 5, -3.5, 3.5, 0.05)
    apply_scan(grid, scan)
    for r in range(grid.height):
        for c in range(grid.width):
            cell = Cell(c, r)
            if grid.value(cell) != FREE:
                continue
            px, py = grid.center_of(cell)
            assert world.contains(px, py), (px, py)
            # Between two beams the outline is a chord of a round object: 2 cm of slack.
            assert all(math.hypot(o.x - px, o.y - py) >= o.radius - 0.02 for o in objects)
    # Each return lies on a surface: occupied, and the space just before it free.
    for i, rng_ in enumerate(scan.ranges):
        if scan.is_hit(rng_) and rng_ > 0.3:
            a = scan.beam_angle(i)
            assert (
                grid.value_at(x + (rng_ + 0.0125) * math.cos(a), y + (rng_ + 0.0125) * math.sin(a))
                == OCCUPIED
            )


def test_a_path_on_a_rotated_map_keeps_clear_in_the_map_frame():
    grid = OccupancyGrid(80, 60, 0.05, Pose2D(1.0, -2.0, 0.7), bytearray(80 * 60))
    for r in range(20, 60):
        grid.set(Cell(40, r), OCCUPIED)  # a wall across most of the map
    inflated = inflate(grid, 0.2)
    a, b = grid.center_of(Cell(10, 50)), grid.center_of(Cell(70, 50))
    path = plan_path(inflated, a, b)
    assert path.length > math.dist(a, b) + 0.5  # round the wall's end, not through it
    _assert_path_is_clear(inflated, path)
