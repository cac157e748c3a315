"""A Blender scene of a run folder (:class:`~quadnav.runs.Run`), saved as a .blend
and rendered headless, laid out as the WPI RBE595 course set its scenes up in Blender.

The scene (names in quotes are the Blender object names):

- ``"block.NNN"``: each block as a cube in its map colour, in the collection ``"blocks"``;
- ``"boundary"``: the map's boundary as a black box of alpha :data:`BOUNDARY_ALPHA`, its
  faces turned inward and culled from behind, so the far walls and the floor frame the
  scene while the near ones leave the view clear;
- ``"start"`` a red sphere, ``"goal"`` a green one;
- ``"tree"``: the explored tree as thin tubes, at most :data:`MAX_TREE_EDGES` evenly
  spread edges; ``"path"`` in translucent red around the thinner ``"trajectory"`` in
  orange (curves, in the colours of the matplotlib figures);
- ``"drone"``: an X-frame quadrotor at its true size (arm length and body size of the
  vehicle flown) scaled up by the object's scale so it shows at the map's size, keyframed
  on every frame at :data:`DEFAULT_FPS` frames per second of flight time with the
  recorded position and attitude quaternion (the last flight.csv sample at or before each
  frame's time); the file opens, and renders, at the middle frame of the flight;
- cameras ``"oblique"`` (an elevated three-quarter perspective view) and ``"top"`` (a
  top-down orthographic view), both framing the map's boundary, and a sun for the Eevee
  and Cycles engines.

A render uses the Workbench engine (colours as set, studio light; Eevee works headless too
but compiles shaders for half a minute). Every ``bpy`` import happens inside the
functions here, so importing this module needs no Blender.
"""

from __future__ import annotations

import io
import math
import os
import sys
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
from matplotlib.colors import to_rgb

from quadnav.errors import QuadnavError
from quadnav.files import atomic_output
from quadnav.runs import Run
from quadnav.viz.style import (
    DRONE_COLOR,
    DRONE_SCALE,
    GOAL_COLOR,
    PATH_COLOR,
    START_COLOR,
    TRAJECTORY_COLOR,
    TREE_COLOR,
)
from quadnav.viz.thinning import evenly_spread

#: The cameras a render can be taken from, named by the image file's stem.
CAMERAS = ("oblique", "top")
#: Opacity of the black boundary box (the course's setting).
BOUNDARY_ALPHA = 0.344
#: Tree edges in the scene at most; a larger tree is thinned to an evenly spread subset.
MAX_TREE_EDGES = 3_000
DEFAULT_FPS = 24
DEFAULT_SIZE = (1280, 720)
#: Radii as fractions of the map's largest extent: start/goal spheres, path, trajectory,
#: tree edges.
SPHERE_RADIUS = 0.02
PATH_RADIUS = 0.0045
TRAJECTORY_RADIUS = 0.0025
TREE_RADIUS = 0.001
#: Opacity of the path, so the trajectory inside it shows where they run together.
PATH_ALPHA = 0.6
#: The oblique camera: elevation and azimuth of the view direction, degrees (the 3D
#: figures' view), and horizontal field of view, degrees.
OBLIQUE_ELEVATION = 30.0
OBLIQUE_AZIMUTH = -60.0
OBLIQUE_FOV = 50.0
#: Room left around the map in a camera's frame, as a fraction of the frame.
FRAME_MARGIN = 0.04
BACKGROUND = (1.0, 1.0, 1.0)
INSTALL_HINT = "pip install 'quadnav[blender]'"

# The unit cube's corners (numbered by bits x, y, z) and outward-facing quads.
_CORNERS = np.array([[(i >> 0) & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
_QUADS = ((0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5))


@dataclass(frozen=True)
class SceneInfo:
    """What :func:`build_scene` put in the scene: blocks, tree edges shown and in all,
    animation frames (0 without a flight) and frames per second."""

    blocks: int
    tree_edges: int
    tree_edges_total: int
    frames: int
    fps: int


def require_bpy() -> ModuleType:
    """Blender's ``bpy`` module; QuadnavError saying how to install it if it is missing."""
    try:
        import bpy
    except ModuleNotFoundError as error:
        if error.name != "bpy":
            raise
        raise QuadnavError(f"quadnav blender needs Blender's Python module bpy, which is not "
                           f"installed: {INSTALL_HINT} (bpy wheels exist for Python "
                           f"3.11)") from None
    except ImportError as error:
        reason = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise QuadnavError(f"Blender's Python module bpy is installed but cannot be loaded: "
                           f"{reason}") from None
    return bpy


def render_camera(path: str | Path) -> str:
    """The camera a render at ``path`` is taken from, named by the file's stem; QuadnavError
    for another stem, an ending other than .png, or a missing folder."""
    path = Path(path)
    if path.stem not in CAMERAS or path.suffix.lower() != ".png":
        raise QuadnavError(f"{path}: expected a render named by its camera: "
                           f"{' or '.join(name + '.png' for name in CAMERAS)}")
    if not path.parent.is_dir():
        raise QuadnavError(f"{path}: folder {str(path.parent)!r} does not exist")
    return path.stem


def check_blend_path(path: str | Path) -> None:
    """QuadnavError unless ``path`` ends in .blend and its folder exists."""
    path = Path(path)
    if path.suffix.lower() != ".blend":
        raise QuadnavError(f"{path}: expected a file name ending in .blend")
    if not path.parent.is_dir():
        raise QuadnavError(f"{path}: folder {str(path.parent)!r} does not exist")


def linear_rgb(srgb: Sequence[float]) -> tuple[float, float, float]:
    """Blender's scene-linear RGB of an sRGB colour (3,) in [0, 1]."""
    c = np.clip(np.asarray(srgb, dtype=float), 0.0, 1.0)
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return (float(linear[0]), float(linear[1]), float(linear[2]))


def frame_rows(t: np.ndarray, fps: int) -> np.ndarray:
    """Rows of a flight record with times ``t`` (N,), s, shown on frames 1, 2, ... at
    ``fps``: the last sample at or before each frame's time, one frame past the end at
    most so the last frame shows the last sample."""
    times = np.arange(math.ceil(t[-1] * fps - 1e-9) + 1) / fps
    return np.clip(np.searchsorted(t, times + 1e-9, side="right") - 1, 0, len(t) - 1)


@contextmanager
def _blender_output() -> Iterator[None]:
    """Keep Blender's own printing (render progress, GPU notes, operator reports) off the
    terminal; on an error other than a QuadnavError it is shown on stderr before the
    error goes on."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    reports = io.StringIO()  # what reaches Python's own streams
    failed = False
    with tempfile.TemporaryFile() as log:
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        try:
            with redirect_stdout(reports), redirect_stderr(reports):
                yield
        except QuadnavError:
            raise
        except BaseException:
            failed = True
            raise
        finally:
            for fd, copy in enumerate(saved, start=1):
                os.dup2(copy, fd)
                os.close(copy)
            if failed:
                log.seek(0)
                sys.stderr.write(log.read().decode(errors="replace") + reports.getvalue())


class _SceneBuilder:
    """Builds the scene of one run into Blender's current (emptied) file."""

    def __init__(self, bpy: ModuleType, run: Run) -> None:
        import bmesh
        import mathutils

        self.bpy, self.bmesh, self.mathutils = bpy, bmesh, mathutils
        self.run = run
        self.scene = bpy.context.scene
        self.size = float(np.max(run.world.extent))
        self.materials: dict[tuple, object] = {}

    def material(self, name: str, srgb: Sequence[float], alpha: float = 1.0):
        """A material of the colour ``srgb`` shared by every object of that colour, set for
        Workbench (viewport colour) and for Eevee and Cycles (Principled BSDF)."""
        rgb = linear_rgb(srgb)
        key = (*np.round(rgb, 6), alpha)
        if key in self.materials:
            return self.materials[key]
        material = self.bpy.data.materials.new(name)
        material.diffuse_color = (*rgb, alpha)
        material.use_nodes = True
        shader = material.node_tree.nodes["Principled BSDF"]
        shader.inputs["Base Color"].default_value = (*rgb, 1.0)
        shader.inputs["Alpha"].default_value = alpha
        if alpha < 1.0:
            material.blend_method = "BLEND"
            material.use_backface_culling = True
            material.show_transparent_back = False
        self.materials[key] = material
        return material

    def add(self, name: str, data, material=None, collection=None):
        """A new object ``name`` holding ``data``, linked to ``collection`` (default the
        scene's) and given ``material``."""
        obj = self.bpy.data.objects.new(name, data)
        (collection or self.scene.collection).objects.link(obj)
        if material is not None:
            obj.data.materials.append(material)
        return obj

    def mesh(self, name: str, vertices: np.ndarray, faces: Sequence[Sequence[int]]):
        mesh = self.bpy.data.meshes.new(name)
        mesh.from_pydata(vertices.tolist(), [], [list(face) for face in faces])
        mesh.update()
        return mesh

    def curve(self, name: str, lines: Sequence[np.ndarray], radius: float, material):
        """An object of poly-line tubes of ``radius``, m, through each (K, 3) array."""
        curve = self.bpy.data.curves.new(name, "CURVE")
        curve.dimensions = "3D"
        curve.bevel_depth = radius
        curve.bevel_resolution = 1
        curve.use_fill_caps = True
        for points in lines:
            spline = curve.splines.new("POLY")
            spline.points.add(len(points) - 1)
            spline.points.foreach_set("co", np.column_stack(
                [points, np.ones(len(points))]).ravel())
        return self.add(name, curve, material)

    def sphere(self, name: str, center: np.ndarray, color: str) -> None:
        mesh = self.bpy.data.meshes.new(name)
        bm = self.bmesh.new()
        self.bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16,
                                       radius=SPHERE_RADIUS * self.size)
        bm.to_mesh(mesh)
        bm.free()
        mesh.shade_smooth()
        self.add(name, mesh, self.material(name, to_rgb(color))).location = center

    def world(self) -> int:
        """Blocks, boundary, start and goal; returns the number of blocks."""
        world = self.run.world
        cube = self.mesh("block", _CORNERS - 0.5, _QUADS)
        cube.materials.append(None)  # a slot each block fills with its own colour
        blocks = self.bpy.data.collections.new("blocks")
        self.scene.collection.children.link(blocks)
        for row, (box, color) in enumerate(zip(world.blocks, world.colors, strict=True)):
            obj = self.add(f"block.{row:03d}", cube, collection=blocks)
            obj.location = (box[:3] + box[3:]) / 2
            obj.scale = box[3:] - box[:3]
            obj.material_slots[0].link = "OBJECT"
            obj.material_slots[0].material = self.material(f"block.{row:03d}", color)
        inward = [face[::-1] for face in _QUADS]
        boundary = self.mesh("boundary", world.lower + _CORNERS * world.extent, inward)
        self.add("boundary", boundary, self.material("boundary", (0.0, 0.0, 0.0),
                                                     BOUNDARY_ALPHA))
        for name, point, color in (("start", world.start, START_COLOR),
                                   ("goal", world.goal, GOAL_COLOR)):
            if point is not None:
                self.sphere(name, point, color)
        return len(world.blocks)

    def plan(self) -> tuple[int, int]:
        """The tree, the path and the trajectory; returns the tree edges shown and in all."""
        edges = self.run.tree_edges()
        shown = evenly_spread(edges, MAX_TREE_EDGES)
        if len(shown):
            self.curve("tree", shown, TREE_RADIUS * self.size,
                       self.material("tree", TREE_COLOR[:3]))
        if self.run.path is not None:
            self.curve("path", [self.run.path], PATH_RADIUS * self.size,
                       self.material("path", to_rgb(PATH_COLOR), PATH_ALPHA))
        if self.run.trajectory is not None:
            self.curve("trajectory", [self.run.trajectory.position],
                       TRAJECTORY_RADIUS * self.size,
                       self.material("trajectory", to_rgb(TRAJECTORY_COLOR)))
        return len(shown), len(edges)

    def drone_mesh(self):
        """An X-frame quadrotor at the vehicle's true size: body box, two arms, four rotor
        discs and a nose on +x (body frame, x forward, z up)."""
        bmesh = self.bmesh
        vehicle = self.run.parameters.get("vehicle", {})
        try:
            arm = float(vehicle["arm_length"])
            body = np.array(vehicle["body_size"], dtype=float).reshape(3)
        except (KeyError, TypeError, ValueError):
            raise QuadnavError(f"{self.run.folder / 'parameters.json'}: expected vehicle "
                               "arm_length and body_size (3 numbers)") from None
        bm = bmesh.new()

        def box(center, size, angle=0.0) -> None:
            matrix = (self.mathutils.Matrix.Translation(center)
                      @ self.mathutils.Matrix.Rotation(angle, 4, "Z")
                      @ self.mathutils.Matrix.Diagonal((*size, 1.0)))
            bmesh.ops.create_cube(bm, size=1.0, matrix=matrix)

        box((0, 0, 0), body)
        box((body[0] / 2, 0, 0), body * (0.5, 0.3, 0.6))  # the nose
        thickness = 0.25 * body[2]
        for angle in (math.pi / 4, -math.pi / 4):
            box((0, 0, 0), (2 * arm, thickness, thickness), angle)
        for k in range(4):
            angle = math.pi / 4 + k * math.pi / 2
            center = (arm * math.cos(angle), arm * math.sin(angle), body[2] / 2)
            bmesh.ops.create_cone(bm, cap_ends=True, segments=24, radius1=0.45 * arm,
                                  radius2=0.45 * arm, depth=0.1 * body[2],
                                  matrix=self.mathutils.Matrix.Translation(center))
        mesh = self.bpy.data.meshes.new("drone")
        bm.to_mesh(mesh)
        bm.free()
        return mesh, arm

    def drone(self, fps: int) -> int:
        """The drone keyframed along the flight; returns the number of frames."""
        flight = self.run.flight
        mesh, arm = self.drone_mesh()
        obj = self.add("drone", mesh, self.material("drone", to_rgb(DRONE_COLOR)))
        obj.scale = (max(1.0, DRONE_SCALE * self.size / arm),) * 3
        obj.rotation_mode = "QUATERNION"
        rows = frame_rows(flight.t, fps)
        for frame, row in enumerate(rows, start=1):
            obj.location = flight.position[row]
            obj.rotation_quaternion = flight.attitude[row]
            obj.keyframe_insert("location", frame=frame)
            obj.keyframe_insert("rotation_quaternion", frame=frame)
        return len(rows)

    def cameras(self) -> None:
        """The cameras of :data:`CAMERAS`, framing the boundary at the render's aspect."""
        world, render = self.run.world, self.scene.render
        aspect = render.resolution_y / render.resolution_x
        center = (world.lower + world.upper) / 2
        corners = world.lower + _CORNERS * world.extent  # (8, 3)
        top = self.bpy.data.cameras.new("top")
        top.type = "ORTHO"
        top.sensor_fit = "HORIZONTAL"
        top.ortho_scale = (1 + 2 * FRAME_MARGIN) * max(world.extent[0],
                                                       world.extent[1] / aspect)
        top.clip_end = 3 * world.extent[2] + 1.0
        self.add("top", top).location = (center[0], center[1], world.upper[2] + world.extent[2])
        oblique = self.bpy.data.cameras.new("oblique")
        oblique.sensor_fit = "HORIZONTAL"
        elevation, azimuth = math.radians(OBLIQUE_ELEVATION), math.radians(OBLIQUE_AZIMUTH)
        back = np.array([math.cos(elevation) * math.cos(azimuth),
                         math.cos(elevation) * math.sin(azimuth), math.sin(elevation)])
        obj = self.add("oblique", oblique)
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = self.mathutils.Vector(-back).to_track_quat("-Z", "Y")
        self.bpy.context.view_layer.update()
        # Blender's own fit (the one of View Selected) at a field of view narrowed by the
        # margin, then the field of view widened again.
        fov = math.radians(OBLIQUE_FOV)
        oblique.angle = 2 * math.atan(math.tan(fov / 2) / (1 + 2 * FRAME_MARGIN))
        location, _ = obj.camera_fit_coords(self.bpy.context.evaluated_depsgraph_get(),
                                            corners.ravel().tolist())
        oblique.angle = fov
        obj.location = location
        oblique.clip_end = 4 * float(np.linalg.norm(np.array(location) - center))
        self.scene.camera = obj

    def settings(self, size: tuple[int, int], fps: int) -> None:
        """Render size, frame rate, Workbench with material colours, a plain background
        and the Standard view transform, so colours render as given."""
        scene = self.scene
        scene.render.resolution_x, scene.render.resolution_y = size
        scene.render.resolution_percentage = 100
        scene.render.fps = fps
        scene.render.fps_base = 1.0
        scene.render.engine = "BLENDER_WORKBENCH"
        scene.display.shading.light = "STUDIO"
        scene.display.shading.color_type = "MATERIAL"
        scene.display_settings.display_device = "sRGB"
        scene.view_settings.view_transform = "Standard"
        scene.view_settings.look = "None"
        scene.render.image_settings.file_format = "PNG"
        scene.world = self.bpy.data.worlds.new("background")
        scene.world.color = linear_rgb(BACKGROUND)
        sun = self.bpy.data.lights.new("sun", "SUN")
        self.add("sun", sun).rotation_euler = (math.radians(40), 0.0, math.radians(30))


def build_scene(bpy: ModuleType, run: Run, size: tuple[int, int] = DEFAULT_SIZE,
                fps: int = DEFAULT_FPS) -> SceneInfo:
    """Empty Blender's current file and build the scene of ``run`` in it (see the module);
    ``size`` is the render's width and height, pixels."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    builder = _SceneBuilder(bpy, run)
    builder.settings(size, fps)
    blocks = builder.world()
    shown, total = builder.plan()
    frames = builder.drone(fps) if run.flight is not None else 0
    builder.cameras()
    scene = builder.scene
    scene.frame_start, scene.frame_end = 1, max(frames, 1)
    scene.frame_set(max(frames, 1) // 2 + 1)
    return SceneInfo(blocks, shown, total, frames, fps)


def save_blend(bpy: ModuleType, path: str | Path) -> None:
    """Save Blender's current file to ``path``, whole or not at all."""
    bpy.context.preferences.filepaths.save_version = 0  # no backup of the empty temporary file
    with atomic_output(path) as tmp, _blender_output():
        bpy.ops.wm.save_as_mainfile(filepath=str(tmp), compress=True, copy=True)


def render_still(bpy: ModuleType, camera: str, path: str | Path) -> None:
    """Render the current frame from ``camera`` to the PNG ``path``, whole or not at all."""
    scene = bpy.context.scene
    scene.camera = bpy.data.objects[camera]
    with atomic_output(path) as tmp, _blender_output():
        bpy.ops.render.render()
        bpy.data.images["Render Result"].save_render(filepath=str(tmp), scene=scene)


def write_blender(run: Run, blend: str | Path, renders: Sequence[str | Path] = (),
                  size: tuple[int, int] = DEFAULT_SIZE, fps: int = DEFAULT_FPS) -> SceneInfo:
    """Build the scene of ``run``, save it to ``blend`` and render each of ``renders``
    (named by camera, see :func:`render_camera`).

    Raises:
        QuadnavError: a bad output name or folder, or no bpy installed; nothing is written.
    """
    check_blend_path(blend)
    cameras = [render_camera(path) for path in renders]
    with _blender_output():  # bpy 4.x prints NumPy 2's notice about a module of its own
        bpy = require_bpy()  # built for NumPy 1.x (harmless) and a headless audio warning
        info = build_scene(bpy, run, size, fps)
    save_blend(bpy, blend)
    for camera, path in zip(cameras, renders, strict=True):
        render_still(bpy, camera, path)
    return info
