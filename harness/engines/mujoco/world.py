"""A world: one compiled MuJoCo model per topology, its data, and the numpy views of the
data's arena the per-step readout reads through (each attribute read through the bindings
makes a new array, with an address check: the views are made once).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass, field

import mujoco
import numpy as np


def _layout(model: mujoco.MjModel) -> bytes:
    """Every size of ``model`` that MjData's layout depends on (its integer ``n*`` counts).

    The bindings hold them in one array (``_sizes``, named by ``_size_fields``: a private
    field of the mujoco bindings, pinned in pyproject.toml; one read,
    ~1 µs, where the ~100 attributes read one by one cost ~25 µs a newly compiled polygon
    model; tests/engines/test_mujoco_reads.py checks it against the attributes).
    """
    return model._sizes.tobytes()



@dataclass
class _Model:
    """A world: one compiled model per topology (ground, shape kinds) and its data.

    Without a polygon the model's geometry is rewritten in place for each scene
    (:meth:`MujocoEngine._hold`); with one, ``compiled`` keeps a compiled model per
    geometry, all stepping the same ``MjData`` when their layouts agree. The numpy views
    (of the data: :func:`_use_data`; of the model's edited arrays: ``edits``) are made once:
    each attribute read through the bindings makes a new array.
    """

    model: mujoco.MjModel
    data: mujoco.MjData
    body_geoms: list[int]  # geom id of each scene body
    body_ids: list[int]
    extents: list[float]  # body_extent of each scene body's shape
    geometry: tuple | None = None  # geometry_key of the geometry the model holds
    # Polygon worlds: geometry key -> [MjModel, configured]; layout -> MjData.
    compiled: OrderedDict | None = None
    datas: dict | None = None
    spec: mujoco.MjSpec | None = None  # polygon worlds: the parsed spec, never compiled
    # Editable worlds: views of geom_size, geom_rbound, geom_aabb, bvh_aabb, body_mass and
    # body_inertia, and each body's row of bvh_aabb.
    edits: tuple | None = None
    bvh_rows: list[int] | None = None
    # What the model holds now: (settings snapshot, e, μ, derived), see _configure.
    configured: tuple | None = None
    dt: float = 0.0  # s, the time step the model holds
    normal_sign: float = 0.0  # +1/-1 once the run's first contact is read, 0 before
    last_depth: float = math.inf  # m, the previous contact step's largest penetration
    # Views of ``data`` (_use_data): qpos, qvel, xpos, xmat; the contacts (_contact_rows).
    qpos: object = None
    qvel: object = None
    xpos: object = None
    xmat: object = None
    contact_rows: object = None  # (n, 7): dist, pos, frame[:3] of each contact slot
    first_contact: object = None  # the first slot's dist, pos and frame[:3]
    first_two: object = None  # the first two slots' rows
    first_geom2: object = None  # the first slot's geom2 (1 int)
    contact_address: int = 0  # where ``contact_rows`` starts: the data's arena
    arena: object = None  # the arena as doubles, from ``contact_address``
    # Views of efc_force in ``arena`` by (ncon, nefc) (_force_view), for the data, model
    # and options held: emptied when one of them changes.
    force_views: dict = field(default_factory=dict)
    # Contact views made so far, by data (a polygon world's datas take turns).
    contact_views: dict = field(default_factory=dict)



def _use_data(world: _Model, data: mujoco.MjData) -> None:
    """Make ``world`` step ``data``, with views of its arrays made once (they live in the
    data's buffer and arena, fixed for its life; the contacts' views are made at the first
    contact the data reports, :func:`_contact_rows`)."""
    world.data = data
    world.qpos, world.qvel = data.qpos, data.qvel
    world.xpos, world.xmat = data.xpos, data.xmat
    (world.contact_rows, world.first_contact, world.first_two, world.first_geom2, world.arena,
     world.contact_address) = world.contact_views.get(id(data), (None,) * 5 + (0,))
    # Keyed by id(data): safe since world.datas holds every data for the world's life.
    if world.force_views:
        world.force_views = {}



# MuJoCo's mjContact begins with dist, pos[3] and frame[9]: the first 7 doubles (the frame's
# first row is the normal) are read as one row.
_CONTACT_HEAD = 7


def _contact_rows(world: _Model, contact) -> None:
    """Make ``world.contact_rows`` a view of the data's contacts as rows of ``dist, pos`` and
    the normal (the frame's first row), and ``world.first_geom2`` one of the first slot's
    ``geom2`` (``contact``: ``data.contact`` at a contact step).

    MuJoCo puts the contacts at the start of the data's arena (``mj_collision``; the arena
    is allocated with the data and ``mj_resetData`` points the contacts at its start), one
    fixed address for the data's life, and the bindings make new arrays of them at every
    read (with the address check); a view over every slot the arena can hold, read
    up to ``ncon``, costs one read per step. Made at the data's first contact (the fields'
    order checked) and kept by data (a polygon world's datas take turns).
    """
    distances = contact.dist
    address = distances.ctypes.data
    stride = distances.strides[0]
    if (contact.pos.ctypes.data - address, contact.frame.ctypes.data - address) != (8, 32):
        raise RuntimeError("mujoco: mjContact no longer begins with dist, pos, frame")
    rows = np.lib.stride_tricks.as_strided(
        distances, shape=(world.data.narena // stride, _CONTACT_HEAD),
        strides=(stride, 8), writeable=False)
    arena = np.lib.stride_tricks.as_strided(
        distances, shape=(world.data.narena // 8,), strides=(8,), writeable=False)
    views = (rows, rows[0], rows[:2], contact.geom2[:1], arena, address)
    world.contact_views[id(world.data)] = views
    (world.contact_rows, world.first_contact, world.first_two, world.first_geom2, world.arena,
     world.contact_address) = views



def _force_view(world: _Model, count: int, rows: int):
    """``data.efc_force`` (``rows`` long, ``count`` contacts) as a view of the arena, kept in
    ``world.force_views`` (read through the bindings, a new array each step: ~1 µs, and
    ~5 µs more for its address).

    MuJoCo allocates the constraint arrays in the arena after the contacts, in a fixed
    order of sizes that, in these planar models (dense Jacobian, one island), follow from
    the model's layout and options and the contact and row counts alone; the address is
    taken at the first step with each pair of counts, and taken again after the data, the
    model or the options change. Returns the bindings' array where the view cannot be made
    (an address off the arena's doubles).
    """
    forces = world.data.efc_force
    offset, rest = divmod(forces.ctypes.data - world.contact_address, 8)
    if rest or offset < 0 or offset + rows > len(world.arena):
        return forces
    view = world.force_views[count, rows] = world.arena[offset:offset + rows]
    return view
