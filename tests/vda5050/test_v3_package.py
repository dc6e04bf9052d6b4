"""Package contract of vda5050.v3 and vda5050.adapt: exports, Struct options, wire names."""

from __future__ import annotations

import enum
import inspect

import msgspec
import pytest

from vda5050 import adapt, v3
from vda5050.v3 import enums as enums3


def _structs() -> list[type[msgspec.Struct]]:
    return sorted(
        {
            obj
            for obj in vars(v3).values()
            if isinstance(obj, type) and issubclass(obj, msgspec.Struct) and obj is not v3.VDAStruct
        },
        key=lambda cls: cls.__name__,
    )


def test_everything_in_all_is_importable() -> None:
    for module in (v3, adapt, enums3):
        for name in module.__all__:
            assert hasattr(module, name), f"{module.__name__}.{name}"
    exported = {id(getattr(v3, name)) for name in v3.__all__}
    assert all(id(cls) in exported for cls in v3.MESSAGE_TYPES.values())


@pytest.mark.parametrize("cls", _structs(), ids=lambda c: c.__name__)
def test_struct_options(cls: type[msgspec.Struct]) -> None:
    assert cls.__doc__
    parameters = inspect.signature(cls).parameters.values()
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in parameters)
    for field in msgspec.structs.fields(cls):
        # 2.x's Trajectory keeps degree=1; the 3.0 one makes every optional field None.
        if not field.required and (cls.__name__, field.name) != ("Trajectory", "degree"):
            assert field.default is None, f"{cls.__name__}.{field.name}"
    if cls.__module__.startswith("vda5050.v3."):
        assert cls.__struct_config__.omit_defaults


def test_snake_case_attributes_map_to_camel_case_wire_names() -> None:
    explicit = {"allowedDeviationXY"}
    for cls in _structs():
        for field in msgspec.structs.fields(cls):
            if field.encode_name in explicit or "." in field.encode_name:
                continue
            head, *rest = field.name.split("_")
            assert field.encode_name == head + "".join(p.title() for p in rest), field


def test_enums_are_upper_snake_str_enums() -> None:
    for name in enums3.__all__:
        cls = getattr(enums3, name)
        assert issubclass(cls, enum.StrEnum), name
        if name != "ActionType":
            assert all(m.value == m.value.upper() for m in cls), name
    assert v3.ConnectionState.CONNECTION_BROKEN == "CONNECTION_BROKEN"
    assert v3.OperatingMode.TEACH_IN == "TEACH_IN"
    assert "FLOAT" not in {m.value for m in v3.ValueDataType}
    assert "AUTOACK" not in {m.value for m in v3.ActiveEmergencyStop}
