"""A swarm: copies of a profile's vehicle on one bus, each its own vehicle and MAVLink system.

Vehicle ``i`` (from 1) of ``n`` follows PX4's multi-vehicle SITL (``Tools/simulation/sitl_multiple_run.sh``):
its name is ``[swarm] names[i-1]``, else ``v<i>``; MAV_SYS_ID is ``i`` (``ROMFS/px4fmu_common/init.d-posix/rcS``
sets it to the instance + 1); its seed is the profile's for vehicle 1 and one drawn from the profile's and ``i``
for the others (numpy's SeedSequence), so no two vehicles see the same sensor noise and a seed still gives one
swarm flight; each MAVLink link binds ``i - 1`` ports further and sends ``i - 1`` ports further,
but a ground station's link (``shared_remote``) sends where every vehicle's does, as PX4's GCS links all send to
14550 (``px4-rc.mavlink``); its simulated home lies ``(i - 1) × [swarm] spacing_m`` east of the profile's.
Vehicles after the first join the first one's bus (its router's endpoint), over Zenoh's queued transport.
"""

from __future__ import annotations

import copy
import dataclasses
import re

import numpy as np

from stack.mathlib.geo import MapProjection
from stack.params import catalogue
from stack.supervisor.profile import ModuleEntry, Profile

_PORT = re.compile(r":(\d+)$")
LINK_MODULE = "mavlink"
HOME = ("SIH_LOC_LAT0", "SIH_LOC_LON0")


def vehicle_names(profile: Profile, count: int) -> list[str]:
    """The names of a swarm of ``count`` vehicles of ``profile``; a ValueError when the profile names fewer."""
    if count < 1:
        raise ValueError(f"a swarm has at least one vehicle, not {count}")
    most = int(catalogue.get("MAV_SYS_ID").max)
    if count > most:
        raise ValueError(f"a swarm has at most {most} vehicles, each its own MAVLink system (MAV_SYS_ID), not {count}")
    if not profile.swarm_names:
        return [f"v{i}" for i in range(1, count + 1)]
    if len(profile.swarm_names) < count:
        raise ValueError(f"{profile.path}: [swarm] names {len(profile.swarm_names)} vehicles, not {count}")
    return list(profile.swarm_names[:count])


def vehicle_copy(profile: Profile, index: int, count: int, join: str = "") -> Profile:
    """Vehicle ``index`` (from 1) of a swarm of ``count`` of ``profile`` (see the module docstring); ``join``: the
    bus endpoint it connects to (the first vehicle's, or the hub of a swarm spread over machines)."""
    if not 1 <= index <= count:
        raise ValueError(f"vehicle {index} of a swarm of {count}")
    if profile.hosts:
        raise ValueError(f"{profile.path}: a swarm of a profile spread over hosts ([hosts]) is not supported")
    shift = index - 1
    modules = [_module_copy(m, index, shift * profile.swarm_spacing_m) for m in profile.modules]
    # The vehicles' routers are linked to one another: with Zenoh's low-latency transport, which writes straight to
    # the socket, the first vehicle's router (every other one's link) locked up as they all closed at once.
    bus = dataclasses.replace(profile.bus, low_latency=False)
    if join:
        bus = dataclasses.replace(bus, connect=(*bus.connect, join))
    return dataclasses.replace(
        profile,
        vehicle=vehicle_names(profile, count)[shift],
        seed=vehicle_seed(profile.seed, index),
        modules=modules,
        processes=copy.deepcopy(profile.processes),
        bus=bus,
    )


def vehicle_seed(seed: int, index: int) -> int:
    """The seed of vehicle ``index`` (from 1) of a swarm flown with ``seed``."""
    return seed if index == 1 else int(np.random.SeedSequence([seed & 0xFFFFFFFFFFFFFFFF, index]).generate_state(1)[0])


def _module_copy(entry: ModuleEntry, index: int, east_m: float) -> ModuleEntry:
    params = dict(entry.params)
    declared = {p.name for p in entry.cls.PARAMS}
    if "MAV_SYS_ID" in declared:
        params["MAV_SYS_ID"] = index
    if east_m and all(name in declared for name in HOME):
        lat, lon = (float(params.get(name, catalogue.get(name).default)) for name in HOME)
        params["SIH_LOC_LAT0"], params["SIH_LOC_LON0"] = MapProjection(lat, lon).reproject(0.0, east_m)
    args = dict(entry.args)
    if entry.module == LINK_MODULE and index > 1:
        args["device"] = _shifted(str(args.get("device", "")), index - 1, entry.name)
        if not args.get("shared_remote"):
            args["remote"] = _shifted(str(args.get("remote", "")), index - 1, entry.name)
    return dataclasses.replace(entry, params=params, args=args)


def _shifted(endpoint: str, by: int, link: str) -> str:
    """``endpoint`` with its port ``by`` further; empty stays empty."""
    if not endpoint:
        return endpoint
    if endpoint.startswith("serial:"):
        raise ValueError(f"{link}: the vehicles of a swarm cannot share the serial link {endpoint}")
    m = _PORT.search(endpoint)
    if m is None:
        raise ValueError(f"{link}: {endpoint!r} has no port to give each vehicle its own")
    port = int(m.group(1)) + by
    if port > 65535:
        raise ValueError(f"{link}: {endpoint!r} leaves no port for vehicle {by + 1}")
    return endpoint[: m.start(1)] + str(port)
