"""What a case function receives: :class:`Case` (built in the worker from a :class:`CaseSpec`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drake_mh.errors import InvalidArgument
from drake_mh.study.seeding import case_id, case_key, derive_seed


@dataclass(frozen=True)
class CaseSpec:
    """The picklable description of one case sent to a worker.

    Attributes:
        params: grid values in grid order.
        key: stable text key.
        case_id: file-safe id.
        seed: derived case seed.
        instance_seed: derived seed of the case's instance (key without the method field).
        quick: whether the quick grid runs.
        index: position in the grid (for ordering only).
    """

    params: dict[str, Any]
    key: str
    case_id: str
    seed: int
    instance_seed: int
    quick: bool
    index: int

    @classmethod
    def build(cls, params: dict[str, Any], study_seed: int, method_key: str, quick: bool, index: int) -> CaseSpec:
        """Derives key, id and seeds from grid values and the study seed."""
        key = case_key(params)
        instance_key = case_key(params, exclude=(method_key,))
        return cls(
            params=dict(params),
            key=key,
            case_id=case_id(key),
            seed=derive_seed(study_seed, key),
            instance_seed=derive_seed(study_seed, "instance:" + instance_key),
            quick=quick,
            index=index,
        )


@dataclass
class Case:
    """One case as seen by the study's case function.

    Attributes:
        params: this case's grid values (``case["robot"]`` reads one).
        key: stable text key, e.g. ``robot=panda/method=pso/rep=3``.
        case_id: file-safe id used for array / artifact file names.
        seed: case seed derived from the study seed and ``key``.
        rng: ``numpy.random.Generator`` seeded with ``seed``.
        instance_seed: seed derived from the key without the method field.
        instance_rng: generator seeded with ``instance_seed`` (same problem for every method).
        quick: the quick grid is running.
        attachments: ``{name: str | bytes}`` saved with :meth:`attach`.
    """

    params: dict[str, Any]
    key: str
    case_id: str
    seed: int
    instance_seed: int
    quick: bool = False
    rng: np.random.Generator = field(init=False, repr=False)
    instance_rng: np.random.Generator = field(init=False, repr=False)
    attachments: dict[str, str | bytes] = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        self.rng = np.random.default_rng(self.seed)
        self.instance_rng = np.random.default_rng(self.instance_seed)

    @classmethod
    def from_spec(cls, spec: CaseSpec) -> Case:
        """Builds the case object from its spec."""
        return cls(
            params=dict(spec.params),
            key=spec.key,
            case_id=spec.case_id,
            seed=spec.seed,
            instance_seed=spec.instance_seed,
            quick=spec.quick,
        )

    def __getitem__(self, name: str) -> Any:
        return self.params[name]

    def get(self, name: str, default: Any = None) -> Any:
        """Returns a grid value or ``default``."""
        return self.params.get(name, default)

    def attach(self, name: str, data: str | bytes) -> str:
        """Saves a file beside the record, e.g. a Meshcat static HTML animation.

        Args:
            name: plain file name (no folders), e.g. ``"animation.html"``.
            data: text or bytes.

        Returns:
            The path the file will have, relative to the output folder.

        Raises:
            InvalidArgument: a name with a folder part, or data that is not str/bytes.
        """
        if not name or "/" in name or "\\" in name or name in (".", ".."):
            raise InvalidArgument(f"attachment name must be a plain file name like 'anim.html', got {name!r}")
        if not isinstance(data, (str, bytes)):
            raise InvalidArgument(f"attachment {name!r} must be str or bytes, got {type(data).__name__}")
        self.attachments[name] = data
        return f"artifacts/{self.case_id}/{name}"
