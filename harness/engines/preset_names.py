"""The names of the engines' presets: the two preset *roles* every engine has, the names an
engine gives a role where the role's name would mislead, and the labels users see and type.

Beneath the adapters' contract (which resolves a typed preset name with :func:`preset_role`)
and re-exported by :mod:`harness.engines`; the names live here, not in the adapters, so
reports and scenario files can be read where the engine is not installed.
"""

from __future__ import annotations

#: The preset roles every engine has, in display order.
PRESET_ROLES: tuple[str, ...] = ("defaults", "accurate")

# engine -> {role: the name users see}, where the role's name would mislead. MuJoCo's second
# preset matches the bounce (e·|v_n|) but not a dissipative law: it creates kinetic energy in
# a part of the impacts with m_nt ≠ 0 (docs/engines.md, 'MuJoCo').
_PRESET_NAMES: dict[str, dict[str, str]] = {
    "mujoco": {"accurate": "matched-bounce"},
}


def preset_label(engine: str, role: str | None) -> str | None:
    """The name users see for ``engine``'s preset ``role`` (the role itself unless renamed)."""
    if role is None:
        return None
    return _PRESET_NAMES.get(engine, {}).get(role, role)


def source_label(engine: str, role: str | None) -> str:
    """``"engine.name"`` as shown to users, e.g. ``"mujoco.matched-bounce"``; the engine
    alone for ``role`` None. The one place an (engine, role) pair becomes a label."""
    return engine if role is None else f"{engine}.{preset_label(engine, role)}"


def renamed_roles(engine: str) -> dict[str, str]:
    """``{role: name}`` of ``engine``'s renamed roles (empty when none is renamed)."""
    return dict(_PRESET_NAMES.get(engine, {}))


def preset_role(engine: str | None, name: str) -> str:
    """The role a preset name typed by a user selects.

    ``engine`` None (a choice for every engine, as the CLIs' ``--preset``): a role, or any
    engine's name for a role. With an engine: that engine's shown name, or a role the engine
    has not renamed. Raises ``ValueError`` naming the allowed names; a renamed role's old name
    is refused with its new one (``mujoco.accurate`` -> use ``matched-bounce``).
    """
    if engine is None:
        for role in PRESET_ROLES:
            if name == role or any(names.get(role) == name for names in _PRESET_NAMES.values()):
                return role
        raise ValueError(f"unknown preset {name!r}; allowed: {', '.join(preset_choices())}")
    names = _PRESET_NAMES.get(engine, {})
    for role in PRESET_ROLES:
        if name == preset_label(engine, role):
            return role
    if name in names:
        raise ValueError(f"engine {engine!r} calls its {name!r} preset {names[name]!r}: "
                         f"use {engine}.{names[name]}")
    allowed = ", ".join(preset_label(engine, role) for role in PRESET_ROLES)
    raise ValueError(f"engine {engine!r}: unknown preset {name!r}; allowed: {allowed}")


def preset_choices() -> tuple[str, ...]:
    """Every name ``--preset`` accepts: the roles, then the engines' own names for them."""
    renamed = [name for names in _PRESET_NAMES.values() for name in names.values()]
    return tuple(dict.fromkeys([*PRESET_ROLES, *renamed]))
