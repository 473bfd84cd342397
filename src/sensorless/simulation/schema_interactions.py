"""Scenario-file sections of intended contacts and collisions: guiding, clamp, impact.

The contact entries ``profile: guiding``, ``clamp`` and ``impact`` (the
profiles of :mod:`sensorless.simulation.interaction_profiles`), the union
:data:`Contact` of every contact entry a scenario may hold (those of
:mod:`sensorless.simulation.schema_parts` and these), and the section
``random_interactions`` (:func:`sensorless.simulation.interactions.draw_interactions`).
:class:`~sensorless.simulation.schema.ScenarioFile` assembles them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Literal, TypeAlias

from pydantic import Field, model_validator
from pydantic_core import PydanticCustomError

from ..io.file_schema import Count, FileModel, NonNegative, Positive, one_of
from .schema_parts import HalfSineContact, Link, PushContact, RecordedContact, _ContactSpec

__all__ = [
    "ClampContact",
    "Contact",
    "GuidingContact",
    "ImpactContact",
    "RandomInteractionsSpec",
]


class GuidingContact(_ContactSpec):
    """A person's guiding hand (intended): slow ramp up, hold, ramp down (``GuidingHand``)."""

    profile: Literal["guiding"]
    start: NonNegative = Field(description="Start [s].")
    ramp: Positive = Field(description="Rise time [s].")
    hold: NonNegative = Field(description="Time at the peak [s].")
    release: Positive = Field(description="Fall time [s].")
    peak: NonNegative = Field(description="Force held [N].")


class ClampContact(_ContactSpec):
    """Clamp (collision): linear build-up, hold, release (``Clamp``)."""

    profile: Literal["clamp"]
    start: NonNegative = Field(description="Start [s].")
    build: Positive = Field(description="Time from first contact to the peak [s].")
    hold: NonNegative = Field(description="Time at the peak [s].")
    release: Positive = Field(description="Fall time [s].")
    peak: NonNegative = Field(description="Clamping force [N].")


class ImpactContact(_ContactSpec):
    """Impact (collision): fast rise, short fall (``Impact``)."""

    profile: Literal["impact"]
    start: NonNegative = Field(description="Start [s].")
    rise: Positive = Field(description="Rise time, shorter than the duration [s].")
    duration: Positive = Field(description="Length [s].")
    peak: NonNegative = Field(description="Largest force [N].")

    @model_validator(mode="after")
    def _rise_within(self) -> ImpactContact:
        if not self.rise < self.duration:
            raise PydanticCustomError(
                "impact_rise",
                "rise ({rise} s) must be shorter than duration ({duration} s)",
                {"field": "rise", "rise": self.rise, "duration": self.duration},
            )
        return self


if TYPE_CHECKING:
    Contact: TypeAlias = (
        "HalfSineContact | PushContact | RecordedContact | GuidingContact | ClampContact"
        " | ImpactContact"
    )
else:
    Contact = one_of(
        "contact",
        {
            "half_sine": HalfSineContact,
            "push": PushContact,
            "recorded": RecordedContact,
            "guiding": GuidingContact,
            "clamp": ClampContact,
            "impact": ImpactContact,
        },
        key="profile",
        expected="a mapping with profile half_sine, push, recorded, guiding, clamp or impact",
    )


class RandomInteractionsSpec(FileModel):
    """Guiding, clamp and impact contacts drawn from the run seed (``draw_interactions``)."""

    count: Count = Field(description="Number of contacts in the run.")
    kinds: Annotated[list[Literal["guiding", "clamp", "impact"]], Field(min_length=1)] = Field(
        default=["guiding", "clamp", "impact"], description="Kinds to choose from."
    )
    links: Annotated[list[Link], Field(min_length=1)] | None = Field(
        default=None, description="Links to choose from (null: 2..n)."
    )
    point_range: NonNegative = Field(
        default=0.05, description="Half-width of the cube of points [m]."
    )
    spread: NonNegative = Field(
        default=0.3, description="Spread of the direction around the point's motion [-]."
    )
    min_gap: NonNegative = Field(default=1.0, description="Least time between contacts [s].")
    margin: NonNegative = Field(default=0.5, description="Contact-free time at both ends [s].")
