"""The one table of camjax's models: the command line's ``--model``, ``solve``'s
``TypeError`` and the generic tests all read it (as ``camjax.laws``'s registry is for laws).
It imports nothing heavy (the command line's ``--help`` reads it before JAX is imported);
``camjax.models`` re-exports it.

Adding a model: its module under ``camjax/models/``, one ``ModelEntry`` in ``MODELS``, its lazy
names in ``camjax/models/__init__.py``, an example in ``tests/helpers.py``, an entry in
the API page.
"""

from __future__ import annotations

import dataclasses
import importlib


@dataclasses.dataclass(frozen=True)
class ModelEntry:
    """One model as the registry knows it.

    Attributes:
        name: the model's name on the command line (``camjax ct --model NAME:V1,V2``).
        class_name: its class, defined in ``camjax.models.<module>``.
        module: the module that defines it (imported on first use: most import diffrax).
        parameters: ``(field, placeholder)`` of the parameters ``--model NAME:...`` sets,
            in order, after the period ratio.
        damping: whether the model has a viscous ``damping`` field (``--damping``).
        swept: whether its period ratio can be swept (``camjax.ct_curve``): every
            SDOF-family model; not a machine model that carries its own laws.
        summary: what the scene adds, in a few words.
    """

    name: str
    class_name: str
    module: str
    parameters: tuple[tuple[str, str], ...] = ()
    damping: bool = True
    swept: bool = True
    summary: str = ""

    def model_class(self) -> type:
        """The model's class (importing its module)."""
        return getattr(importlib.import_module(f"camjax.models.{self.module}"), self.class_name)

    @property
    def usage(self) -> str:
        """``NAME`` or ``NAME:P1,P2`` as ``--model`` takes it."""
        placeholders = ",".join(p for _, p in self.parameters)
        return f"{self.name}:{placeholders}" if placeholders else self.name

    def counted(self, values) -> tuple:
        """``values`` as a tuple if one for each of ``parameters``, else a ``ValueError``
        saying which (``backlash takes 2 parameters, BK and DN (backlash:BK,DN), got 1``)."""
        values = tuple(values)
        if len(values) != len(self.parameters):
            names = [p for _, p in self.parameters]
            listed = ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else "".join(names)
            count = f"{len(names)} parameter{'' if len(names) == 1 else 's'}"
            raise ValueError(f"{self.name} takes {count}{', ' + listed if names else ''} "
                             f"({self.usage}), got {len(values)}")
        return values

    def template(self, values=(), damping: float = 0.0):
        """The model at period ratio 1 with ``values`` for ``parameters`` (a sweep's
        template); ``ValueError`` naming what is wrong."""
        values = self.counted(values)
        fields = {field: float(v) for (field, _), v in zip(self.parameters, values)}
        if self.damping:
            fields["damping"] = float(damping)
        elif damping:
            raise ValueError(f"{self.name} has no damping ratio (leave the damping at 0)")
        return self.model_class()(period_ratio=1.0, **fields)


MODELS: tuple[ModelEntry, ...] = (
    ModelEntry("spring-mass", "SpringMass", "_spring_mass",
               summary="the linear SDOF: payload on an elastic transmission"),
    ModelEntry("friction", "CoulombFriction", "_friction", (("friction", "MU"),),
               summary="Coulomb friction on the payload"),
    ModelEntry("backlash", "Backlash", "_backlash", (("backlash", "BK"), ("natural_deceleration", "DN")),
               summary="a clearance in the transmission"),
    ModelEntry("two-mass", "TwoMass", "_two_mass",
               (("stiffness_ratio", "K"), ("inertia_ratio", "M")), damping=False,
               summary="an elastic input drive"),
    ModelEntry("swinging-follower", "SwingingFollower", "_swinging_follower", damping=False,
               swept=False, summary="a flexible swinging roller follower in a grooved cam"),
)
"""Every model, simplest first."""


def model_entry(name: str, *, swept: bool = False) -> ModelEntry:
    """The registry's entry named ``name`` (``swept=True``: among the sweepable ones);
    ``ValueError`` listing the valid names."""
    choices = [m for m in MODELS if m.swept or not swept]
    for entry in choices:
        if entry.name == str(name).strip().lower():
            return entry
    raise ValueError(f"unknown model {name!r}; valid: {', '.join(m.usage for m in choices)}")


def model_class_names() -> str:
    """The models' class names, for messages."""
    return ", ".join(m.class_name for m in MODELS)
