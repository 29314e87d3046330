"""Drake's settings: their docs, Drake's defaults and the two presets."""

from __future__ import annotations

#: The discrete contact approximations Drake 1.51 offers (MultibodyPlantConfig's
#: ``discrete_contact_approximation``): SAP's three and the older TAMSI solver.
APPROXIMATIONS = ("lagged", "similar", "sap", "tamsi")

SETTING_DOCS: dict[str, str] = {
    "time_step": "s, MultibodyPlantConfig.time_step (default 0.001)",
    "discrete_contact_approximation": "lagged | similar | sap | tamsi (default lagged); "
    "lagged and similar are SAP's convex forms of Hunt–Crossley, sap ignores the "
    "dissipation, tamsi is the older solver (deprecated by Drake after 1.51)",
    "penetration_allowance": "m, MultibodyPlantConfig.penetration_allowance: Drake's estimate "
    "of the point-contact stiffness and dissipation where none is given (default 0.001)",
    "stiction_tolerance": "m/s, MultibodyPlantConfig.stiction_tolerance, the slip speed "
    "below which friction is regularised (default 1e-4)",
    "contact_steps": "null (Drake's own stiffness from penetration_allowance) or the steps "
    "an undamped contact of the scene's normal effective mass lasts: the point-contact "
    "stiffness k = m_nn·(π / (contact_steps·time_step))²",
    "hunt_crossley_dissipation": "null (Drake's own estimate), a number (s/m), or "
    "\"restitution\": from e, the approach speed and contact_steps (the discrete map)",
    "max_steps": "step cap; reported as status no-separation when hit in contact",
    "approach_steps": "steps of free flight before first touch (0 = touching at the first step)",
}

_DEFAULTS = {
    "time_step": 1e-3,
    "discrete_contact_approximation": "lagged",
    "penetration_allowance": 1e-3,
    "stiction_tolerance": 1e-4,
    "contact_steps": None,
    "hunt_crossley_dissipation": None,
    "max_steps": 20000,
    "approach_steps": 0.0,
}
PRESETS: dict[str, dict] = {
    "defaults": dict(_DEFAULTS),
    "accurate": dict(
        _DEFAULTS,
        # The contact's stiffness from the scene's normal effective mass so that it lasts
        # contact_steps steps, and Hunt–Crossley's d from e through Drake's own discrete
        # (implicit) contact: the bounce is e·v on a central drop (docs/engines.md, 'Drake').
        # 500 steps: the implicit step's own loss, exp(-π²/(2·500)) = 0.990 of the bounce
        # where no d >= 0 can make up for it (e > 0.990), stays within 1%. 1 µs steps: a
        # 0.5 ms contact (as MuJoCo's), short enough that the body barely turns or sinks
        # meanwhile (a 5 ms one rolled the ellipse's contact point off the lowest point and
        # sank the Kharaz sphere). TAMSI, measured against SAP: the same bounces and
        # departures at 2.8x less CPU, and no loss of the normal impulse beside a large
        # tangential speed (SAP's lagged bounces at 0.88 of e·v at v_n/v_t = 1e-3); Drake
        # deprecates it after 1.51, the last Drake for Python 3.11 (docs/engines.md, 'Drake').
        time_step=1e-6,
        discrete_contact_approximation="tamsi",
        contact_steps=500,
        hunt_crossley_dissipation="restitution",
    ),
}
