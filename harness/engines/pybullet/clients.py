"""pybullet's DIRECT clients between uses, and the batch that holds many impacts in one.

Connecting a client costs ~20-50 ms and ``resetSimulation`` ~2 ms (package docstring,
"Reuse and determinism" and "Many impacts"): clients are connected without the renderer
plugin, emptied and kept per settings, and a batch's impacts are laid in slices of the
engine's y in the order that keeps Bullet's broad-phase tree shallow.
"""

from __future__ import annotations

from dataclasses import dataclass

from harness.engines.pybullet.presets import _RUN_ONLY
from harness.engines.pybullet.world import _World
from harness.engines.quiet import import_quietly

p = import_quietly("pybullet")  # not `import pybullet as p`: it prints its build time


def _connect() -> int:
    """A new DIRECT client without its renderer plugin.

    pybullet's built-in TinyRenderer makes a visual mesh of every new link from its
    collision shape (for a sphere, most of a ``createMultiBody`` call); nothing
    here renders. Plugins touch no physics (the bit-identity tests pin the runs).
    """
    client = p.connect(p.DIRECT)
    renderer = p.loadPlugin("tinyRendererPlugin", physicsClientId=client)  # its id, if loaded
    if renderer >= 0:
        p.unloadPlugin(renderer, physicsClientId=client)
    return client


@dataclass
class _Client:
    """A DIRECT client and what it keeps between uses."""

    uid: int  # pybullet's physicsClientId
    plane: int | None = None  # run_many: the static plane it keeps for ground batches
    impacts: int = 0  # run_many: impacts built in it since it was last reset


def _reset_client(client: _Client) -> None:
    """Empty ``client``: Bullet deletes its dynamics world and makes a new one."""
    p.resetSimulation(physicsClientId=client.uid)
    client.plane, client.impacts = None, 0


def _remove_bodies(client: int, worlds) -> None:
    """Remove the bodies of ``worlds`` (batch impacts) from ``client``."""
    for world in worlds:
        for uid in world.bodies:
            p.removeBody(uid, physicsClientId=client)


def _slice_offsets(sizes: list[float], gap: float) -> list[float]:
    """Each batch impact's y (its bases'), for impacts of ``sizes`` (m, their largest body
    extents) made in list order: slices ``gap`` apart, laid out along y in bit-reversed
    order of making (0, n/2, n/4, 3n/4, ...).

    Bullet's broad phase keeps a bounding-volume tree that it does not rebalance as leaves
    are added or moved: slices made in order along a line make it a chain, and every body
    made, first moved (its start state) or removed then walks it (a cost that grows with
    every body already in the client). Made in bit-reversed order, each new body splits
    the longest gap so far, and the tree stays shallow.
    """
    count = len(sizes)
    bits = max(count - 1, 0).bit_length()
    # Slot order along y: by the bit reversal of the slot's index.
    along = sorted(range(count), key=lambda slot: int(format(slot, f"0{bits}b")[::-1] or "0", 2))
    offsets = [0.0] * count
    offset = previous = 0.0
    for place, slot in enumerate(along):
        size = sizes[slot]
        if place:
            offset += previous + size + gap
        previous = size
        offsets[slot] = offset
    return offsets


def _settings_key(settings) -> tuple:
    """The settings a world is built with (all but the per-run ones), as a key."""
    return tuple((k, settings[k]) for k in sorted(settings) if k not in _RUN_ONLY)


class _Batch:
    """A client holding many impacts (one :class:`_World` view each)."""

    __slots__ = ("body_b", "client", "clock", "dt", "held", "left", "pool_key", "slot_of",
                 "slots")

    def __init__(self, held: _Client, pool_key: tuple, dt: float) -> None:
        self.held, self.pool_key, self.dt = held, pool_key, dt
        self.client = held.uid  # -1 once released
        self.slots: list[_World] = []
        self.slot_of: dict[int, int | None] = {}  # body unique id -> slot (the plane: None)
        self.body_b: list[int] = []  # per slot, its body B's unique id (bodies[-1])
        self.left: set[int] = set()  # slots whose bodies are still in the client
        self.clock = [0]  # steps taken (its impacts' _World.clock)
