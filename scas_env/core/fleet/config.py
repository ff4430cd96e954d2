"""Configuration of a fleet: aircraft, missions, demand, crew, spares, background removals.

A frozen validated dataclass like ``Scenario`` and ``CostModel``
(:class:`~scas_env.actuator.config.Validated`: every number declared with its unit, range
and source; unknown keys and bad values refused with a message naming the field, the value
and what is allowed). Files: ``FleetConfig.load("case.toml")`` reads the ``[fleet]`` table
(one of :data:`~scas_env.actuator.config.FILE_SECTIONS`, beside ``[scenario]`` and
``[costs]``) or the fields at the top level; ``save`` writes them under ``[fleet]``.
The demand and the spares are sub-tables (``[fleet.demand]``, ``[fleet.spares]``).

Mission types are listed by name (:data:`~scas_env.actuator.mission_types.MISSION_TYPES`)
with, in the same order, each one's value when flown, its penalty when not flown and its
probability in the demand's mix (``demand.mission_mix``).

>>> cfg = FleetConfig()
>>> cfg.aircraft, cfg.actuators_per_aircraft, cfg.flights_per_mission, cfg.n_actuators
(8, 3, 2, 24)
>>> round(cfg.base_missions_per_day, 3)
4.384
>>> FleetConfig(mission_types=("standard", "windy"))  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
ValueError: FleetConfig.mission_types[1] = 'windy' is not a mission type; allowed: [...]
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from scas_env.actuator.config import Validated, param
from scas_env.actuator.mission_types import MISSION_TYPES
from scas_env.core.costs import MAX_USD, CostModel, amount_usd
from scas_env.core.fleet.demand import DemandModel
from scas_env.core.fleet.resources import NO_BASE_STOCK, SparesSpec
from scas_env.utils.table_checks import finite_numbers

#: the table of a configuration file that holds a FleetConfig
SECTION = "fleet"


@dataclass(frozen=True)
class SparesConfig(Validated):
    """Spares: stock at the start, base stock (order-up-to level) and lead times per kind.

    Kinds: spring kits and seal kits (a part replaced on the aircraft), and whole actuators
    from a rotable pool (both parts new; the removed unit comes back from the shop after the
    turnaround: a base stock equal to the pool). ``base_stock = -1``: never reordered
    (the initial stock only: the actions order nothing).
    """

    spring_kit_initial: float = param(
        2, "kits", lo=0, hi=10_000, integer=True, source="two kits per kind on the shelf [B]"
    )
    spring_kit_base_stock: float = param(
        2,
        "kits",
        lo=NO_BASE_STOCK,
        hi=10_000,
        integer=True,
        source="(S-1, S) replenishment up to the initial shelf [B]; -1: never reordered "
        "(no action orders)",
    )
    spring_kit_lead_days: float = param(
        10,
        "days",
        lo=0,
        hi=365,
        integer=True,
        source="a standard spring from the distributor [B]; ref §8.2: 'spare availability "
        "dominates' unscheduled downtime",
    )
    seal_kit_initial: float = param(
        2, "kits", lo=0, hi=10_000, integer=True, source="two kits per kind on the shelf [B]"
    )
    seal_kit_base_stock: float = param(
        2,
        "kits",
        lo=NO_BASE_STOCK,
        hi=10_000,
        integer=True,
        source="(S-1, S) replenishment up to the initial shelf [B]; -1: never reordered "
        "(no action orders)",
    )
    seal_kit_lead_days: float = param(
        10, "days", lo=0, hi=365, integer=True, source="a seal kit from the distributor [B]"
    )
    actuator_pool: float = param(
        2,
        "actuators",
        lo=0,
        hi=10_000,
        integer=True,
        source="serviceable actuators in the rotable pool for 24 installed [B]; a background "
        "removal needs one (0: such an aircraft waits for none ever comes)",
    )
    actuator_turnaround_days: float = param(
        30,
        "days",
        lo=0,
        hi=365,
        integer=True,
        source="shop turnaround of a removed actuator [B] (a component overhaul shop's weeks)",
    )
    lead_spread_days: float = param(
        0,
        "days",
        lo=0,
        hi=365,
        integer=True,
        source="lead times uniform on lead +- spread (whole days) [B]; 0: fixed lead times",
    )
    unlimited: float = param(
        0, "bool", lo=0, hi=1, integer=True, source="1: every spare always on hand (degenerate)"
    )

    def _check(self) -> None:
        for kind, lead in (
            ("spring_kit", self.spring_kit_lead_days),
            ("seal_kit", self.seal_kit_lead_days),
            ("actuator", self.actuator_turnaround_days),
        ):
            if self.lead_spread_days > lead:
                raise ValueError(
                    f"SparesConfig.lead_spread_days = {self.lead_spread_days} days must be <= "
                    f"every lead time ({kind}: {lead} days): a lead time is never negative"
                )

    def spec(self) -> SparesSpec:
        """The resource model's :class:`~scas_env.core.fleet.resources.SparesSpec`."""
        pool = int(self.actuator_pool)
        return SparesSpec(
            initial=(int(self.spring_kit_initial), int(self.seal_kit_initial), pool),
            base_stock=(int(self.spring_kit_base_stock), int(self.seal_kit_base_stock), pool),
            lead_days=(
                int(self.spring_kit_lead_days),
                int(self.seal_kit_lead_days),
                int(self.actuator_turnaround_days),
            ),
            lead_spread_days=(int(self.lead_spread_days),) * 3,
            unlimited=(bool(self.unlimited),) * 3,
        )


@dataclass(frozen=True)
class FleetConfig(Validated):
    """A fleet of helicopters with SCAS actuators, its missions and shared resources."""

    aircraft: float = param(
        8,
        "aircraft",
        lo=1,
        hi=1000,
        integer=True,
        source="a base of 8 helicopters, an assumed medium operator [B]",
    )
    actuators_per_aircraft: float = param(
        3,
        "actuators",
        lo=1,
        hi=8,
        integer=True,
        source="a three-axis SCAS (AH-1 'three-axis ... SCAS', ref §1.1)",
    )
    flights_per_mission: float = param(
        2, "flights", lo=1, hi=16, integer=True, source="2 flights per day (ref §8.2, range 1-6)"
    )
    episode_days: float = param(
        365, "days", lo=1, hi=36_500, integer=True, source="one year: one seasonal cycle [B]"
    )
    lookahead_days: float = param(
        7,
        "days",
        lo=0,
        hi=365,
        integer=True,
        source="days of the mission schedule known ahead: a weekly flying programme [B]",
    )
    crew_jobs_per_day: float = param(
        1,
        "jobs/day",
        lo=1,
        hi=10_000,
        integer=True,
        source="SCAS jobs (one part replaced, 4-8 MMH for a spring, ref §8.2) the line crew "
        "can fit beside the rest of the fleet's maintenance [B]",
    )
    unlimited_crew: float = param(
        0, "bool", lo=0, hi=1, integer=True, source="1: no crew limit (degenerate fleet)"
    )
    background_removals: float = param(
        1, "bool", lo=0, hi=1, integer=True, source="random removals no feature sees: on"
    )
    mtbur_fh: float = param(
        5000.0,
        "FH",
        lo=100.0,
        hi=1e7,
        source="SCAS actuator MTBUR, all causes, background (ref §8.2: 5,000 FH, 2,000-15,000)",
    )
    background_removal_usd: float = amount_usd(
        25000.0, "an unscheduled removal for a cause outside the model (ref §8.2: $25,000)"
    )
    holding_usd_per_unit_day: float = param(
        0.0,
        "USD/(unit day)",
        lo=0.0,
        hi=MAX_USD,
        source="cost of holding one spare a day [B]; 0: not counted",
    )
    mission_availability_target: float = param(
        0.0,
        "-",
        lo=0.0,
        hi=1.0,
        source="reported beside the measured mission availability; 0: none (the env's "
        "dynamics do not use it)",
    )
    #: a civil multi-role operator [B]: Table 1's mix, utility work (short sectors, loads),
    #: crew changes in gusty wind (the damaging types of docs/fleet.md)
    mission_types: tuple[str, ...] = ("standard", "utility", "offshore_gusts")
    #: 2 flights at the single actuator's $2,500 a flight (CostModel.flight_value_usd)
    mission_value_usd: tuple[float, ...] = (5000.0, 5000.0, 5000.0)
    #: a mission not flown: a substitute aircraft, ref §8.2's "value of lost availability"
    #: $5,000 per grounded day (2,000-20,000), on top of the value not earned
    mission_not_flown_usd: tuple[float, ...] = (5000.0, 5000.0, 5000.0)
    demand: DemandModel = field(default_factory=lambda: DemandModel(mission_mix=(0.5, 0.3, 0.2)))
    spares: SparesConfig = field(default_factory=SparesConfig)

    def _check(self) -> None:
        own = "FleetConfig"
        names = self._names(own)
        for name in ("mission_value_usd", "mission_not_flown_usd"):
            self._amounts(own, name, len(names))
        for name, kind in (("demand", DemandModel), ("spares", SparesConfig)):
            if not isinstance(getattr(self, name), kind):
                got = type(getattr(self, name)).__name__
                raise ValueError(f"{own}.{name} must be a {kind.__name__}, got {got}")
        if len(self.demand.mission_mix) != len(names):
            raise ValueError(
                f"{own}.demand.mission_mix has {len(self.demand.mission_mix)} probabilities but "
                f"{own}.mission_types has {len(names)} types {list(names)}: one per type"
            )
        hours = self.flights_per_mission * self.demand.flight_hours_per_flight
        if hours > 24.0:
            raise ValueError(
                f"{own}: a mission of {self.flights_per_mission} flights of "
                f"{self.demand.flight_hours_per_flight} h lasts {hours} h, more than a day"
            )
        rate = self.base_missions_per_day
        if rate > self.aircraft:
            raise ValueError(
                f"{own}: the mean demand of {rate:.3g} missions a day exceeds the {self.aircraft} "
                "aircraft (one mission each a day) even at full availability; lower "
                "demand.flight_hours_per_aircraft_year or raise flights_per_mission or aircraft"
            )

    def _names(self, own: str) -> tuple[str, ...]:
        names = self.mission_types
        if not isinstance(names, list | tuple) or len(names) == 0:  # a table's keys: no
            raise ValueError(f"{own}.mission_types = {names!r} must be a non-empty list of names")
        for k, name in enumerate(names):
            if not isinstance(name, str) or name not in MISSION_TYPES:
                raise ValueError(
                    f"{own}.mission_types[{k}] = {name!r} is not a mission type; allowed: "
                    f"{sorted(MISSION_TYPES)}"
                )
        if len(set(names)) != len(names):
            raise ValueError(f"{own}.mission_types = {list(names)!r} names a type twice")
        names = tuple(str(n) for n in names)  # plain str (numpy.str_ is saved as YAML badly)
        object.__setattr__(self, "mission_types", names)
        return names

    def _amounts(self, own: str, name: str, n: int) -> None:
        values = getattr(self, name)
        if isinstance(values, str) or not hasattr(values, "__len__") or len(values) != n:
            raise ValueError(
                f"{own}.{name} = {values!r} needs {n} amounts (USD), one per mission type"
            )
        allowed = f"USD must be in [0, {MAX_USD:g}]"
        amounts = finite_numbers(f"{own}.{name}", values, lo=0.0, hi=MAX_USD, allowed=allowed)
        object.__setattr__(self, name, amounts)

    # ------------------------------------------------------------------ derived values
    @property
    def n_actuators(self) -> int:
        """Actuators in the fleet, aircraft x actuators per aircraft."""
        return int(self.aircraft * self.actuators_per_aircraft)

    @property
    def base_missions_per_day(self) -> float:
        """Long-run mean of the daily missions (``DemandModel.base_missions_per_day``)."""
        return self.demand.base_missions_per_day(
            aircraft=int(self.aircraft), flights_per_mission=int(self.flights_per_mission)
        )

    @property
    def crew_capacity(self) -> int | None:
        """Crew jobs a day for :class:`~scas_env.core.fleet.resources.CrewQueue` (None:
        unlimited)."""
        return None if self.unlimited_crew else int(self.crew_jobs_per_day)

    @property
    def background_removal_probability(self) -> float:
        """Probability that a flight ends in a background removal of one actuator:
        ``1 - exp(-h / MTBUR)`` (exponential in flight hours; 0 when switched off)."""
        if not self.background_removals:
            return 0.0
        return -math.expm1(-self.demand.flight_hours_per_flight / self.mtbur_fh)

    @classmethod
    def degenerate(cls) -> FleetConfig:
        """The fleet that is the single env: one aircraft, one actuator, one flight a day
        (one scheduled standard mission a day, worth the single env's flight value),
        unlimited crew and spares, no background removals."""
        demand = DemandModel(
            flight_hours_per_aircraft_year=547.5,  # 1 mission/day x 1 flight x 1.5 h x 365
            arrivals="scheduled",
        )
        return cls(
            aircraft=1,
            actuators_per_aircraft=1,
            flights_per_mission=1,
            lookahead_days=0,
            unlimited_crew=1,
            background_removals=0,
            mission_types=("standard",),
            mission_value_usd=(CostModel().flight_value_usd,),
            mission_not_flown_usd=(0.0,),
            demand=demand,
            spares=SparesConfig(unlimited=1),
        )

    # ------------------------------------------------------------------------ files
    def save(  # type: ignore[override]
        self, path: str | Path, *, section: str | None = SECTION, overwrite: bool = False
    ) -> Path:
        """Write to a TOML/YAML/JSON file under ``[fleet]`` (``section=None``: top level)."""
        return super().save(path, section=section, overwrite=overwrite)

    def to_dict(self) -> dict[str, Any]:
        out = super().to_dict()
        for name in ("mission_types", "mission_value_usd", "mission_not_flown_usd"):
            out[name] = list(out[name])
        out["demand"]["mission_mix"] = list(out["demand"]["mission_mix"])
        return out
