"""Write one rollout episode to one MCAP file that Foxglove opens as is.

Topics (all times are the caller's `t_ns`, nanoseconds of sim time, used as log time and header stamp):

- `/terrain`       foxglove.SceneUpdate      boxes as cubes, heightfields as triangle meshes, frame "world"
- `/tf`            foxglove.FrameTransforms  one per step
- `/joint_states`, `/cpg`, `/step`           JSON with a JSON schema, so Foxglove can plot e.g. `/cpg.a`
- one topic per sensor reading (`hexpipe.sensors`), by the message kind the sensor declares:
  image  foxglove.RawImage  rgb8 (raw, so the bytes read back exactly), e.g. `/camera/image` in frame "camera"
  grid   foxglove.Grid      one float32 "height" field per cell, e.g. `/heightmap` in frame "heading"
  json   JSON with a JSON schema, e.g. `/contacts`

Foxglove types are protobuf-encoded by foxglove-sdk; chunks are zstd-compressed (1 MiB), CRC'd and indexed.
The file appears at `path` only when the writer closes cleanly: it is written to `<path>.tmp` and renamed.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, Protocol, Self

import foxglove
import numpy as np
from foxglove.channels import FrameTransformsChannel, GridChannel, RawImageChannel, SceneUpdateChannel
from foxglove.mcap import MCAPCompression, MCAPWriteOptions
from foxglove.messages import (
    Color,
    CubePrimitive,
    CylinderPrimitive,
    FrameTransform,
    FrameTransforms,
    Grid,
    PackedElementField,
    PackedElementFieldNumericType,
    Point3,
    Pose,
    Quaternion,
    RawImage,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    Timestamp,
    TriangleListPrimitive,
    Vector2,
    Vector3,
)

TOPIC_TERRAIN = "/terrain"
TOPIC_ROBOT = "/robot"
TOPIC_TF = "/tf"
TOPIC_JOINTS = "/joint_states"
TOPIC_CPG = "/cpg"
TOPIC_STEP = "/step"

WORLD_FRAME = "world"
HEIGHT_FIELD = "height"  # the one Grid field name; the Foxglove layout colours and raises cells by it

# foxglove-sdk's defaults spelled out (zstd chunks of ~1 MiB, CRCs, indexes, statistics), except that chunks
# are compressed inline: collect runs one writer per worker process, and per-writer zstd thread pools
# oversubscribe the cores (measured: same mean cost, 2-3x worse p99 step time).
WRITE_OPTIONS = MCAPWriteOptions(
    compression=MCAPCompression.Zstd,
    compression_threads=0,
    chunk_size=1 << 20,
    use_chunks=True,
    emit_statistics=True,
    emit_message_indexes=True,
    emit_chunk_indexes=True,
    calculate_chunk_crcs=True,
    calculate_data_section_crc=True,
    calculate_summary_section_crc=True,
)

_HEIGHTFIELD_RGBA = (0.55, 0.50, 0.45, 1.0)
_JSON_SCHEMA_TITLES = {
    TOPIC_JOINTS: "hexpipe.JointStates",
    TOPIC_CPG: "hexpipe.Cpg",
    TOPIC_STEP: "hexpipe.Step",
}


class BoxLike(Protocol):
    """A terrain box: centre (m, world), full edge lengths (m), yaw about +z (rad), colour (0..1 RGBA)."""

    @property
    def center(self) -> Sequence[float]: ...
    @property
    def size(self) -> Sequence[float]: ...
    @property
    def yaw(self) -> float: ...
    @property
    def rgba(self) -> Sequence[float]: ...


class HeightfieldLike(Protocol):
    """A height grid: `heights[i, j]` (m) is at x = origin[0] + i*cell, y = origin[1] + j*cell (m, world)."""

    @property
    def origin(self) -> Sequence[float]: ...
    @property
    def cell(self) -> float: ...
    @property
    def heights(self) -> np.ndarray: ...


Transform = tuple[str, str, np.ndarray, np.ndarray]  # parent, child, translation xyz (m), quaternion xyzw
# Grid corner position xyz (m) and orientation xyzw in the grid's frame, cell size (m): one number, or
# (along the grid's x, along its y).
GridPose = tuple[np.ndarray, np.ndarray, float | tuple[float, float]]


class SensorMessage(Protocol):
    """One sensor reading to log (`hexpipe.sensors.Message`): kind "image" (payload H x W x 3 uint8), "grid"
    (payload (R x C float32, GridPose)) or "json" (payload a dict; its schema titled `schema`)."""

    @property
    def topic(self) -> str: ...
    @property
    def kind(self) -> str: ...
    @property
    def payload(self) -> Any: ...
    @property
    def frame_id(self) -> str: ...
    @property
    def schema(self) -> str: ...


class EpisodeWriter:
    """Context manager writing one episode; see the module docstring for topics and frames.

    `metadata` becomes MCAP Metadata records (name -> {str: str}), e.g. "episode", "terrain", "params".
    An exception inside the `with` block deletes the temporary file and leaves `path` untouched; an
    existing file at `path` is replaced only on a clean close. Without `with`, call `close()` yourself:
    an unclosed writer leaves just `<path>.tmp` behind.
    """

    def __init__(
        self, path: Path | None, metadata: Mapping[str, Mapping[str, str]], context: foxglove.Context | None = None
    ) -> None:
        """path: the MCAP file, or None to log only to `context`'s other sinks (e.g. a live WebSocket server).

        context: the foxglove Context to create the channels on (default: a fresh one, so one file per writer);
        its sinks must exist already, since a context only delivers to sinks present when a channel is made.
        """
        if path is None and context is None:
            raise ValueError("EpisodeWriter needs a path, a context with a sink, or both")
        self.path = None if path is None else Path(path)
        _check_metadata(metadata)
        self._context = context or foxglove.Context()
        self._closed = False
        self._last_step_ns: int | None = None
        self._json: dict[str, foxglove.Channel] = {}  # made on first use; schema from that message
        self._sensor_channels: dict[str, Any] = {}  # image and grid topics, made on first use
        self._grid_fields = [
            PackedElementField(name=HEIGHT_FIELD, offset=0, type=PackedElementFieldNumericType.Float32)
        ]
        self._writer = None
        if self.path is not None:
            self._tmp = self.path.with_name(self.path.name + ".tmp")
            self.path.parent.mkdir(parents=True, exist_ok=True)
            # The writer must exist before the channels: a context only delivers to sinks present at creation.
            self._writer = foxglove.open_mcap(
                self._tmp, allow_overwrite=True, context=self._context, writer_options=WRITE_OPTIONS
            )
        try:
            for name, record in metadata.items():
                if self._writer is not None:
                    self._writer.write_metadata(name, dict(record))
            self._scene = SceneUpdateChannel(TOPIC_TERRAIN, context=self._context)
            self._robot = SceneUpdateChannel(TOPIC_ROBOT, context=self._context)
            self._tf = FrameTransformsChannel(TOPIC_TF, context=self._context)
        except BaseException:
            self._abort()
            raise

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if exc_type is None:
            self.close()
        else:
            self._abort()

    def log_scene(self, t_ns: int, boxes: Sequence[BoxLike], heightfields: Sequence[HeightfieldLike]) -> None:
        """Log the terrain once per episode: entity "boxes" (cubes) plus one mesh entity per heightfield."""
        stamp = _stamp(t_ns)
        cubes = [
            CubePrimitive(
                pose=Pose(position=_vec3(box.center), orientation=_yaw_quat(float(box.yaw))),
                size=_vec3(box.size),
                color=_color(box.rgba),
            )
            for box in boxes
        ]
        entities = [SceneEntity(timestamp=stamp, frame_id=WORLD_FRAME, id="boxes", cubes=cubes)]
        for k, field in enumerate(heightfields):
            entities.append(
                SceneEntity(timestamp=stamp, frame_id=WORLD_FRAME, id=f"heightfield/{k}", triangles=[_mesh(field)])
            )
        self._scene.log(SceneUpdate(entities=entities), log_time=t_ns)

    def log_robot(self, t_ns: int, shapes: Sequence[Any]) -> None:
        """Log the robot's geometry once: one entity per link, in that link's frame, so /tf animates it.

        shapes: objects with .link, .kind ("cube", "cylinder" along the link's +x, "sphere"), .position,
        .size (full extents, m) and .rgba, e.g. `hexpipe.sim.robot.robot_shapes(spec)`.
        """
        stamp = _stamp(t_ns)
        along_x = Quaternion(x=0.0, y=math.sqrt(0.5), z=0.0, w=math.sqrt(0.5))  # cylinder axis z -> link x
        upright = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)
        per_link: dict[str, dict[str, list]] = {}
        for shape in shapes:
            prims = per_link.setdefault(shape.link, {"cubes": [], "cylinders": [], "spheres": []})
            size = shape.size if shape.kind != "cylinder" else (shape.size[1], shape.size[2], shape.size[0])
            pose = Pose(position=_vec3(shape.position), orientation=along_x if shape.kind == "cylinder" else upright)
            kind = {"cube": (CubePrimitive, "cubes"), "cylinder": (CylinderPrimitive, "cylinders"),
                    "sphere": (SpherePrimitive, "spheres")}[shape.kind]
            prims[kind[1]].append(kind[0](pose=pose, size=_vec3(size), color=_color(shape.rgba)))
        entities = [SceneEntity(timestamp=stamp, frame_id=link, id=f"robot/{link}", frame_locked=True, **prims)
                    for link, prims in per_link.items()]
        self._robot.log(SceneUpdate(entities=entities), log_time=t_ns)

    def log_step(
        self,
        t_ns: int,
        *,
        transforms: Sequence[Transform],
        sensors: Sequence[SensorMessage] = (),
        joints: Mapping[str, Any],
        cpg: Mapping[str, Any],
        step: Mapping[str, Any],
    ) -> None:
        """Log one control step; all its messages share log time `t_ns`, which must increase step to step.

        sensors: the readings, each on its topic (see `SensorMessage`). An image is H x W x 3 uint8. A grid is
        R x C float32 heights (m), cell [r, c] the r-th along the grid's +x and the c-th along its +y, as
        everywhere in hexpipe (HeightField, the height map: rows forward, columns leftward), its pose placing the
        grid's corner (see `GridPose`); Foxglove's Grid runs columns along +x, so the array is stored transposed
        and the reader transposes it back.
        Non-finite floats in the JSON topics are written as null (JSON has no NaN/inf).
        """
        if self._last_step_ns is not None and t_ns <= self._last_step_ns:
            raise ValueError(f"log_step: t_ns={t_ns} must exceed the previous step's {self._last_step_ns}")
        self._last_step_ns = t_ns
        stamp = _stamp(t_ns)
        frames = []
        for parent, child, translation, rotation in transforms:
            x, y, z = np.asarray(translation, float).tolist()
            qx, qy, qz, qw = np.asarray(rotation, float).tolist()
            frames.append(
                FrameTransform(
                    timestamp=stamp,
                    parent_frame_id=parent,
                    child_frame_id=child,
                    translation=Vector3(x=x, y=y, z=z),
                    rotation=Quaternion(x=qx, y=qy, z=qz, w=qw),
                )
            )
        self._tf.log(FrameTransforms(transforms=frames), log_time=t_ns)
        for message in sensors:
            if message.kind == "image":
                self._log_image(message.topic, t_ns, stamp, message.payload, message.frame_id)
            elif message.kind == "grid":
                self._log_grid(message.topic, t_ns, stamp, *message.payload, message.frame_id)
            elif message.kind == "json":
                self._log_json(message.topic, t_ns, message.payload, message.schema)
            else:
                raise ValueError(f"log_step: {message.topic} has unknown message kind {message.kind!r}")
        self._log_json(TOPIC_JOINTS, t_ns, joints)
        self._log_json(TOPIC_CPG, t_ns, cpg)
        self._log_json(TOPIC_STEP, t_ns, step)  # last: a step is complete once its /step is written

    def close(self) -> None:
        """Finish the file (summary, indexes, CRCs), flush it to disk and move it to `path`."""
        if self._closed:
            return
        self._closed = True
        try:
            self._close_channels()
            if self._writer is not None:
                self._writer.close()
                with open(self._tmp, "rb") as f:
                    os.fsync(f.fileno())
                os.replace(self._tmp, self.path)
        except BaseException:
            if self._writer is not None:
                self._tmp.unlink(missing_ok=True)
            raise

    def _abort(self) -> None:
        """Drop the partial file; `path` is never touched."""
        if self._closed:
            return
        self._closed = True
        try:
            self._close_channels()
            if self._writer is not None:
                self._writer.close()
        finally:
            if self._writer is not None:
                self._tmp.unlink(missing_ok=True)

    def _close_channels(self) -> None:
        for name in ("_scene", "_robot", "_tf"):
            if hasattr(self, name):  # absent when __init__ failed part-way
                getattr(self, name).close()
        for channel in [*self._sensor_channels.values(), *self._json.values()]:
            channel.close()

    def _channel(self, topic: str, make: Any) -> Any:
        channel = self._sensor_channels.get(topic)
        if channel is None:
            channel = self._sensor_channels[topic] = make(topic, context=self._context)
        return channel

    def _log_image(self, topic: str, t_ns: int, stamp: Timestamp, rgb: np.ndarray, frame_id: str) -> None:
        if rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
            raise ValueError(f"log_step: {topic} must be H x W x 3 uint8, got {rgb.shape} {rgb.dtype}")
        height, width = rgb.shape[:2]
        message = RawImage(
            timestamp=stamp,
            frame_id=frame_id,
            width=width,
            height=height,
            encoding="rgb8",
            step=3 * width,
            data=rgb.tobytes(),  # C order, whatever the input's strides
        )
        self._channel(topic, RawImageChannel).log(message, log_time=t_ns)

    def _log_grid(self, topic: str, t_ns: int, stamp: Timestamp, heightmap: np.ndarray, pose: GridPose,
                  frame_id: str) -> None:
        if heightmap.ndim != 2:
            raise ValueError(f"log_step: {topic} must be R x C, got shape {heightmap.shape}")
        origin, quaternion, cell = pose
        cell_x, cell_y = np.broadcast_to(np.asarray(cell, float), 2).tolist()  # one number or (x, y)
        rows = heightmap.shape[0]  # = Foxglove columns, along +x
        x, y, z = np.asarray(origin, float).tolist()
        qx, qy, qz, qw = np.asarray(quaternion, float).tolist()
        message = Grid(
            timestamp=stamp,
            frame_id=frame_id,
            pose=Pose(position=Vector3(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw)),
            column_count=rows,
            cell_size=Vector2(x=cell_x, y=cell_y),
            row_stride=4 * rows,
            cell_stride=4,
            fields=self._grid_fields,
            data=np.ascontiguousarray(heightmap.T, dtype="<f4").tobytes(),
        )
        self._channel(topic, GridChannel).log(message, log_time=t_ns)

    def _log_json(self, topic: str, t_ns: int, message: Mapping[str, Any], title: str = "") -> None:
        text = json.dumps(message, separators=(",", ":"), default=_json_default)
        if "NaN" in text or "Infinity" in text:  # rare; Foxglove's JSON.parse rejects these tokens
            text = json.dumps(_finite_or_none(message), separators=(",", ":"), default=_json_default)
        channel = self._json.get(topic)
        if channel is None:
            schema = {"title": title or _JSON_SCHEMA_TITLES[topic], **_json_schema(message)}
            channel = self._json[topic] = foxglove.Channel(topic, schema=schema, context=self._context)
        channel.log(text.encode(), log_time=t_ns)


def _check_metadata(metadata: Mapping[str, Mapping[str, str]]) -> None:
    for name, record in metadata.items():
        if not isinstance(name, str) or not isinstance(record, Mapping):
            raise TypeError(f"metadata: {name!r} must map a str name to a {{str: str}} record")
        bad = [k for k, v in record.items() if not (isinstance(k, str) and isinstance(v, str))]
        if bad:
            raise TypeError(f"metadata[{name!r}]: keys and values must be str (bad keys: {bad[:3]})")


def _stamp(t_ns: int) -> Timestamp:
    sec, nsec = divmod(int(t_ns), 1_000_000_000)
    return Timestamp(sec, nsec)


def _vec3(values: Sequence[float]) -> Vector3:
    x, y, z = (float(v) for v in values)
    return Vector3(x=x, y=y, z=z)


def _yaw_quat(yaw: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def _color(rgba: Sequence[float]) -> Color:
    r, g, b, a = (float(v) for v in rgba)
    return Color(r=r, g=g, b=b, a=a)


def _mesh(field: HeightfieldLike) -> TriangleListPrimitive:
    """Indexed mesh through the nodes: vertex (i, j) is point i*ny + j; each cell is split, as PyBullet does,
    along the diagonal from node (i+1, j) to node (i, j+1) into two counter-clockwise triangles."""
    heights = np.asarray(field.heights, dtype=float)
    nx, ny = heights.shape
    cell = float(field.cell)
    x0, y0 = (float(v) for v in field.origin[:2])
    xs = np.repeat(x0 + cell * np.arange(nx), ny)
    ys = np.tile(y0 + cell * np.arange(ny), nx)
    points = [Point3(x=x, y=y, z=z) for x, y, z in zip(xs.tolist(), ys.tolist(), heights.ravel().tolist(), strict=True)]
    corner = (np.arange(nx - 1)[:, None] * ny + np.arange(ny - 1)[None, :]).ravel()
    p00, p10, p11, p01 = corner, corner + ny, corner + ny + 1, corner + 1
    indices = np.stack([p00, p10, p01, p10, p11, p01], axis=1).ravel().tolist()
    rgba = getattr(field, "rgba", None) or _HEIGHTFIELD_RGBA
    return TriangleListPrimitive(
        pose=Pose(orientation=Quaternion(w=1.0)), points=points, color=_color(rgba), indices=indices
    )


def _json_default(value: Any) -> Any:
    """Let numpy scalars and arrays through json.dumps."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _finite_or_none(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {k: _finite_or_none(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return _finite_or_none(value.tolist())
    if isinstance(value, list | tuple):
        return [_finite_or_none(v) for v in value]
    if isinstance(value, float | np.floating) and not math.isfinite(value):
        return None
    return value


def _json_schema(value: Any) -> dict[str, Any]:
    """JSON schema inferred from a message's first instance: the types Foxglove needs to offer plots."""
    if isinstance(value, Mapping):
        return {"type": "object", "properties": {str(k): _json_schema(v) for k, v in value.items()}}
    if isinstance(value, bool | np.bool_):
        return {"type": "boolean"}
    if isinstance(value, int | float | np.integer | np.floating):
        return {"type": "number"}  # an int field may carry floats later (e.g. reward 0 then 0.3)
    if isinstance(value, str):
        return {"type": "string"}
    if isinstance(value, np.ndarray):
        value = value.tolist()
    if isinstance(value, list | tuple):
        return {"type": "array", "items": _json_schema(value[0]) if len(value) else {}}
    return {}  # None or unknown: leave unconstrained
