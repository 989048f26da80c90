# SPDX-License-Identifier: Apache-2.0
"""The field drawn as an RGB array (numpy uint8, H x W x 3), pure numpy: carpet, markings, goals, robots, ball.

The image covers the carpet (the field plus boundary_width on each side) with the field frame's x to the
right and y up, so row 0 is the carpet's +y edge. Every shape is drawn only inside its bounding box, with
vectorised masks over the pixel centres there. This module imports nothing compiled, so it loads on its own.
"""
import math

import numpy as np

__all__ = ["render_field", "CARPET", "LINE", "GOAL_WALL", "BLUE", "YELLOW", "OTHER_TEAM", "HEADING", "BALL"]

CARPET = (20, 110, 40)
LINE = (255, 255, 255)
GOAL_WALL = (40, 40, 40)
BLUE = (30, 90, 235)
YELLOW = (245, 215, 30)
OTHER_TEAM = (150, 150, 150)  # a team value other than 0 (blue) or 1 (yellow)
HEADING = (15, 15, 15)
BALL = (255, 130, 0)

_GOAL_WALL_THICKNESS = 0.02  # m, drawn centred on the goal's outline
_HEADING_HALF_WIDTH = 0.012  # m
_BALL_MIN_RADIUS_PX = 2.0
_ROBOT_MIN_RADIUS_PX = 1.5
_LINE_MIN_HALF_WIDTH_PX = 0.5  # a marking is at least one pixel wide


class _Canvas:
    """The image and the map from field metres to pixels (pixel centres in metres, per column and row)."""

    def __init__(self, half_x: float, half_y: float, width: int):
        self.half_x = half_x
        self.half_y = half_y
        self.width = width
        self.height = max(1, int(round(width * half_y / half_x)))
        self.sx = width / (2.0 * half_x)  # px per metre, columns
        self.sy = self.height / (2.0 * half_y)  # px per metre, rows
        self.px = 1.0 / min(self.sx, self.sy)  # one pixel in metres (the larger side)
        self.xs = -half_x + (np.arange(self.width) + 0.5) / self.sx
        self.ys = half_y - (np.arange(self.height) + 0.5) / self.sy
        self.image = np.empty((self.height, self.width, 3), dtype=np.uint8)
        self.image[...] = CARPET

    def box(self, xmin: float, xmax: float, ymin: float, ymax: float):
        """Pixel slices (rows, columns) covering a metre box, clipped to the image; None when empty."""
        c0 = max(0, int(math.floor((xmin + self.half_x) * self.sx)))
        c1 = min(self.width, int(math.floor((xmax + self.half_x) * self.sx)) + 1)
        r0 = max(0, int(math.floor((self.half_y - ymax) * self.sy)))
        r1 = min(self.height, int(math.floor((self.half_y - ymin) * self.sy)) + 1)
        if c0 >= c1 or r0 >= r1:
            return None
        return slice(r0, r1), slice(c0, c1)

    def grid(self, rows: slice, cols: slice):
        """The pixel centres of a box in metres: x as a 1 x w row, y as an h x 1 column."""
        return self.xs[cols][None, :], self.ys[rows][:, None]

    def disc(self, cx: float, cy: float, radius: float, colour) -> None:
        """Fill the pixels whose centres lie within radius of (cx, cy)."""
        b = self.box(cx - radius, cx + radius, cy - radius, cy + radius)
        if b is None:
            return
        x, y = self.grid(*b)
        mask = (x - cx) ** 2 + (y - cy) ** 2 <= radius * radius
        self.image[b][mask] = colour

    def segment(self, x1: float, y1: float, x2: float, y2: float, half: float, colour) -> None:
        """Fill the pixels whose centres lie within half of the segment (round caps)."""
        b = self.box(min(x1, x2) - half, max(x1, x2) + half, min(y1, y2) - half, max(y1, y2) + half)
        if b is None:
            return
        x, y = self.grid(*b)
        dx, dy = x2 - x1, y2 - y1
        length2 = dx * dx + dy * dy
        px, py = x - x1, y - y1
        if length2 > 0.0:
            t = np.clip((px * dx + py * dy) / length2, 0.0, 1.0)
            px = px - t * dx
            py = py - t * dy
        mask = px * px + py * py <= half * half
        self.image[b][mask] = colour

    def arc(self, cx: float, cy: float, radius: float, a1: float, a2: float, half: float, colour) -> None:
        """Fill the pixels within half of the arc from a1 counter-clockwise to a2 (a2 - a1 >= 2 pi: a full circle)."""
        outer = radius + half
        b = self.box(cx - outer, cx + outer, cy - outer, cy + outer)
        if b is None:
            return
        x, y = self.grid(*b)
        px, py = x - cx, y - cy
        mask = np.abs(np.sqrt(px * px + py * py) - radius) <= half
        span = a2 - a1
        if abs(span) < 2.0 * math.pi - 1e-9:
            span = span % (2.0 * math.pi)
            mask &= np.mod(np.arctan2(py, px) - a1, 2.0 * math.pi) <= span
        self.image[b][mask] = colour


def _pixel_half_width(thickness: float, canvas: _Canvas) -> float:
    return max(0.5 * float(thickness), _LINE_MIN_HALF_WIDTH_PX * canvas.px)


def render_field(field: dict, robot_ids: np.ndarray, robot_pose: np.ndarray, robot_present: np.ndarray,
                 ball_position: np.ndarray, width: int = 640, robot_radius: float = 0.09,
                 ball_radius: float = 0.0215) -> np.ndarray:
    """Draw the carpet, markings, goal walls, present robots (with heading ticks) and the ball as H x W x 3 uint8."""
    width = int(width)
    if width < 1:
        raise ValueError(f"width must be at least 1 pixel, not {width}")
    length = float(field["field_length"])
    field_width = float(field["field_width"])
    boundary = float(field["boundary_width"])
    if length <= 0.0 or field_width <= 0.0 or boundary < 0.0:
        raise ValueError("field_length and field_width must be positive, boundary_width not negative")
    canvas = _Canvas(0.5 * length + boundary, 0.5 * field_width + boundary, width)

    # Goals: a dark frame (two side walls and the back wall) behind each goal line.
    goal_half = 0.5 * float(field["goal_width"])
    depth = float(field["goal_depth"])
    wall_half = _pixel_half_width(_GOAL_WALL_THICKNESS, canvas)
    for sign in (-1.0, 1.0):
        line_x = sign * 0.5 * length
        back_x = sign * (0.5 * length + depth)
        canvas.segment(back_x, -goal_half, back_x, goal_half, wall_half, GOAL_WALL)
        canvas.segment(line_x, goal_half, back_x, goal_half, wall_half, GOAL_WALL)
        canvas.segment(line_x, -goal_half, back_x, -goal_half, wall_half, GOAL_WALL)

    # Markings, over the goal walls where they meet (the goal line is a marking).
    for x1, y1, x2, y2, thickness in field.get("lines", ()):
        canvas.segment(float(x1), float(y1), float(x2), float(y2), _pixel_half_width(thickness, canvas), LINE)
    for cx, cy, radius, a1, a2, thickness in field.get("arcs", ()):
        canvas.arc(float(cx), float(cy), float(radius), float(a1), float(a2),
                   _pixel_half_width(thickness, canvas), LINE)

    # Robots: a filled disc in the team's colour and a dark tick from the centre toward the yaw.
    ids = np.asarray(robot_ids).reshape(-1, 2)
    pose = np.asarray(robot_pose, dtype=np.float64).reshape(-1, 3)
    present = np.asarray(robot_present, dtype=bool).reshape(-1)
    if not (len(ids) == len(pose) == len(present)):
        raise ValueError(f"robot_ids ({len(ids)}), robot_pose ({len(pose)}) and robot_present ({len(present)}) "
                         "must have one row per robot")
    radius = max(float(robot_radius), _ROBOT_MIN_RADIUS_PX * canvas.px)
    tick_half = max(_HEADING_HALF_WIDTH, 0.5 * canvas.px)
    for i in np.flatnonzero(present):
        x, y, yaw = (float(v) for v in pose[i])
        if not (math.isfinite(x) and math.isfinite(y)):
            continue
        team = int(ids[i, 0])
        canvas.disc(x, y, radius, BLUE if team == 0 else YELLOW if team == 1 else OTHER_TEAM)
        if math.isfinite(yaw):
            tip = radius - tick_half
            canvas.segment(x, y, x + tip * math.cos(yaw), y + tip * math.sin(yaw), tick_half, HEADING)

    # The ball last, so a ball at a robot's dribbler stays visible.
    ball = np.asarray(ball_position, dtype=np.float64).reshape(-1)
    if ball.size >= 2 and math.isfinite(ball[0]) and math.isfinite(ball[1]):
        canvas.disc(float(ball[0]), float(ball[1]), max(float(ball_radius), _BALL_MIN_RADIUS_PX * canvas.px), BALL)
    return canvas.image
