"""The JSON form of the result dataclasses whose fields are all they report (exact σ, the LP bound)."""

from __future__ import annotations

from dataclasses import asdict

from ..jsonable import jsonable


class FieldsToDict:
    """Mixin of a result dataclass: ``to_dict`` gives its fields as JSON-ready values (``shapecond.jsonable``)."""

    __slots__ = ()

    def to_dict(self) -> dict:
        """The fields as a dict of JSON-ready values."""
        return jsonable(asdict(self))
