# SPDX-License-Identifier: Apache-2.0
"""ubersim/render.py: the field as an RGB array, loaded from its file (it needs no compiled module)."""
import importlib.util
import math
import os

import numpy as np
import pytest

_RENDER_PY = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "apps", "python", "ubersim",
                          "render.py")
_spec = importlib.util.spec_from_file_location("ubersim_render_under_test", _RENDER_PY)
render = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(render)

WIDTH = 640


def div_b_field():
    """Div B by hand: 9 x 6 m, goal 1.0 x 0.18, boundary 0.3, penalty area 1.0 x 2.0, centre circle 0.5."""
    hl, hw, t = 4.5, 3.0, 0.01
    lines = [
        (-hl, hw, hl, hw, t),  # the touch lines
        (-hl, -hw, hl, -hw, t),
        (-hl, -hw, -hl, hw, t),  # the goal lines
        (hl, -hw, hl, hw, t),
        (0.0, -hw, 0.0, hw, t),  # the halfway line; no centre line along y = 0, so the circle test is the arc's
        (-hl, 1.0, -hl + 1.0, 1.0, t),  # the left penalty area
        (-hl, -1.0, -hl + 1.0, -1.0, t),
        (-hl + 1.0, -1.0, -hl + 1.0, 1.0, t),
    ]
    return {
        "field_length": 9.0, "field_width": 6.0, "goal_width": 1.0, "goal_depth": 0.18,
        "boundary_width": 0.3, "penalty_area_depth": 1.0, "penalty_area_width": 2.0,
        "center_circle_radius": 0.5, "line_thickness": t,
        "lines": lines,
        "arcs": [(0.0, 0.0, 0.5, 0.0, 2.0 * math.pi, t)],
    }


def pixel(x, y, width=WIDTH, field=None):
    """The (row, column) the field point (x, y) falls in; the carpet is 9.6 x 6.6 m."""
    field = field or div_b_field()
    half_x = field["field_length"] / 2 + field["boundary_width"]
    half_y = field["field_width"] / 2 + field["boundary_width"]
    height = round(width * half_y / half_x)
    return int((half_y - y) * height / (2 * half_y)), int((x + half_x) * width / (2 * half_x))


def draw(robots=(), ball=(10.0, 10.0, 0.0), width=WIDTH, field=None):
    """robots: (team, id, x, y, yaw, present); the ball off the carpet unless given."""
    n = len(robots)
    ids = np.array([[r[0], r[1]] for r in robots], dtype=np.int32).reshape(n, 2)
    pose = np.array([[r[2], r[3], r[4]] for r in robots], dtype=np.float64).reshape(n, 3)
    present = np.array([r[5] for r in robots], dtype=bool).reshape(n)
    return render.render_field(field or div_b_field(), ids, pose, present, np.array(ball, dtype=np.float64),
                               width=width)


def is_carpet(p):
    return tuple(int(v) for v in p) == tuple(render.CARPET) and p[1] > p[0] + 40 and p[1] > p[2] + 40


def is_blue(p):
    r, g, b = (int(v) for v in p)
    return b > 180 and r < 100 and b > g + 80


def is_yellow(p):
    r, g, b = (int(v) for v in p)
    return r > 180 and g > 160 and b < 100


def is_orange(p):
    r, g, b = (int(v) for v in p)
    return r > 200 and 80 < g < 180 and b < 80


def is_white(p):
    return all(int(v) > 230 for v in p)


def test_shape_and_dtype_follow_the_carpets_aspect_ratio():
    img = draw()
    assert img.dtype == np.uint8
    assert img.shape == (440, 640, 3)  # 9.6 x 6.6 m of carpet
    assert draw(width=320).shape == (220, 320, 3)
    assert is_carpet(img[pixel(-2.0, 2.0)])


def test_a_blue_robot_is_blue_where_its_coordinates_map_and_the_carpet_far_away():
    img = draw([(0, 3, -2.0, 1.0, 0.0, True)])
    # Off-centre within the disc, away from the heading tick (which runs along +x from the centre).
    assert is_blue(img[pixel(-2.0, 1.05)])
    assert is_blue(img[pixel(-2.05, 0.97)])
    assert is_carpet(img[pixel(-2.0, 1.2)])
    assert is_carpet(img[pixel(2.0, -1.0)])
    # A row just above the tick crosses ~11 px of the 0.18 m disc at 640 px; it is blue nowhere else.
    row = img[pixel(-2.0, 1.03)[0]]
    blue_cols = [col for col, p in enumerate(row) if is_blue(p)]
    assert len(blue_cols) >= 8 and pixel(-2.09, 1.0)[1] <= min(blue_cols) and max(blue_cols) <= pixel(-1.91, 1.0)[1]


def test_a_yellow_robot_is_yellow_where_its_coordinates_map():
    img = draw([(1, 0, 3.0, -2.0, math.pi / 2, True)])
    assert is_yellow(img[pixel(3.05, -2.0)])
    assert is_yellow(img[pixel(2.95, -2.03)])
    assert not is_blue(img[pixel(3.05, -2.0)])
    assert is_carpet(img[pixel(3.0, -1.8)])
    assert is_carpet(img[pixel(-3.0, 2.0)])


def test_a_robot_not_present_is_not_drawn():
    img = draw([(0, 0, -2.0, 1.0, 0.0, False), (1, 1, 2.0, 1.0, 0.0, True)])
    assert is_carpet(img[pixel(-2.0, 1.05)])
    assert is_yellow(img[pixel(2.0, 1.05)])
    assert not any(is_blue(p) for p in img.reshape(-1, 3))


def test_the_ball_is_an_orange_disc_of_at_least_two_pixels_radius():
    img = draw(ball=(1.3, -0.7, 0.0215))
    assert is_orange(img[pixel(1.3, -0.7)])
    orange = np.array([is_orange(p) for p in img.reshape(-1, 3)])
    assert orange.sum() >= 9  # a 2 px radius disc
    assert is_carpet(img[pixel(1.5, -0.7)])


def test_the_centre_circle_is_white_at_its_radius_and_not_inside():
    field = div_b_field()
    img = draw()
    r = field["center_circle_radius"]
    assert is_white(img[pixel(r, 0.0)])
    assert is_white(img[pixel(-r, 0.0)])
    assert is_white(img[pixel(r / math.sqrt(2), r / math.sqrt(2))])
    assert is_carpet(img[pixel(0.25, 0.1)])
    # Without the arc, nothing else paints that pixel.
    field["arcs"] = []
    assert is_carpet(draw(field=field)[pixel(r, 0.0)])


def test_markings_are_at_least_one_pixel_and_the_goals_are_dark_frames():
    img = draw()
    assert is_white(img[pixel(4.5, 2.0)])  # a goal line, 0.01 m = 0.67 px at 640 px
    assert is_white(img[pixel(0.0, -2.5)])  # the halfway line
    assert is_white(img[pixel(-3.5, 0.3)])  # the penalty area's front
    for sign in (-1, 1):
        back = img[pixel(sign * (4.5 + 0.18), 0.0)]
        assert max(int(v) for v in back) < 80  # the back wall
        assert max(int(v) for v in img[pixel(sign * 4.6, 0.5)]) < 80  # a side wall
        assert is_carpet(img[pixel(sign * 4.6, 0.0)])  # inside the goal
        assert is_carpet(img[pixel(sign * 4.6, 0.7)])  # beside it


def dark_pixels_by_side(img, x, y, yaw, radius=0.09):
    """Count the dark pixels inside the robot's disc in front of and behind its centre along yaw."""
    height, width = img.shape[:2]
    r0, c0 = pixel(x - radius, y + radius)
    r1, c1 = pixel(x + radius, y - radius)
    front = back = 0
    for row in range(r0, r1 + 1):
        for col in range(c0, c1 + 1):
            if max(int(v) for v in img[row, col]) >= 60:
                continue
            px = -4.8 + (col + 0.5) * 9.6 / width - x
            py = 3.3 - (row + 0.5) * 6.6 / height - y
            if px * px + py * py > radius * radius:
                continue
            along = px * math.cos(yaw) + py * math.sin(yaw)
            front += along > 0.01
            back += along < -0.01
    return front, back


@pytest.mark.parametrize("yaw", [0.0, math.pi / 2, math.pi, -math.pi / 2, 0.7, -2.4])
@pytest.mark.parametrize("team", [0, 1])
def test_the_heading_tick_points_the_way_of_yaw(team, yaw):
    x, y = 1.0, -1.0
    img = draw([(team, 2, x, y, yaw, True)])
    front, back = dark_pixels_by_side(img, x, y, yaw)
    assert front >= 3 and front > 2 * back, (front, back)
    # The opposite yaw flips it.
    front2, back2 = dark_pixels_by_side(draw([(team, 2, x, y, yaw + math.pi, True)]), x, y, yaw)
    assert back2 >= 3 and back2 > 2 * front2, (front2, back2)


def test_deterministic_and_robots_off_the_carpet_or_nan_are_harmless():
    robots = [(0, 0, -2.0, 1.0, 0.3, True), (1, 0, 9.0, 9.0, 0.0, True), (1, 1, float("nan"), 0.0, 0.0, True),
              (0, 1, 4.85, 3.35, 1.0, True)]  # the last straddles the carpet's corner
    a = draw(robots, ball=(0.2, 0.1, 0.0))
    b = draw(robots, ball=(0.2, 0.1, 0.0))
    assert np.array_equal(a, b)
