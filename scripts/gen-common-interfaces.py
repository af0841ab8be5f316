#!/usr/bin/env python3
"""Writes the bundled common_interfaces .msg definitions (src/msg/definitions/<pkg>/msg/<Name>.msg)
from the field lists of rosbags' ROS 2 Jazzy type store (PyPI `rosbags`): field names, types,
array kinds, bounds and constants only, one per line, no comments. Service definitions (.srv) are
not in that store and are kept by hand in src/msg/definitions/<pkg>/srv/.

    python3 scripts/gen-common-interfaces.py [--check]

--check compares instead of writing (exit 1 on a difference)."""
import pathlib
import sys

from rosbags.typesys import Stores, get_typestore

PACKAGES = ["builtin_interfaces", "std_msgs", "geometry_msgs", "sensor_msgs", "nav_msgs", "diagnostic_msgs",
            "rosgraph_msgs", "rcl_interfaces", "tf2_msgs", "trajectory_msgs", "visualization_msgs", "action_msgs",
            "unique_identifier_msgs", "shape_msgs", "service_msgs"]
EMPTY = "structure_needs_at_least_one_member"
# Default values, which rosbags' store does not keep: the published definitions' (facts, checked by
# tests/cli/test_msg_cdr.py::test_bundled_defaults). A Quaternion with no w given is the identity.
DEFAULTS = {
    "geometry_msgs/msg/Quaternion": {"x": "0", "y": "0", "z": "0", "w": "1"},
    "rcl_interfaces/msg/ParameterDescriptor": {"read_only": "false", "dynamic_typing": "false"},
}
OUT = pathlib.Path(__file__).resolve().parent.parent / "src" / "msg" / "definitions"


def type_text(spec):
    kind, detail = int(spec[0]), spec[1]
    if kind == 1:  # primitive: (name, string bound)
        base, bound = detail
        return "%s<=%d" % (base, bound) if bound else base
    if kind == 2:  # nested message "pkg/msg/Name" -> "pkg/Name"
        pkg, _, name = detail.split("/")
        return pkg + "/" + name
    inner, size = detail
    if kind == 3:
        return "%s[%d]" % (type_text(inner), size)
    return "%s[<=%d]" % (type_text(inner), size) if size else type_text(inner) + "[]"


def const_text(typ, value):
    if typ == "bool":
        return "true" if value else "false"
    if typ == "string":
        return value
    return repr(value)


def definition(consts, fields, defaults=None):
    defaults = defaults or {}
    lines = ["%s %s=%s" % (t, n, const_text(t, v)) for n, t, v in consts]
    lines += [("%s %s %s" % (type_text(s), n, defaults[n])) if n in defaults else "%s %s" % (type_text(s), n)
              for n, s in fields if n != EMPTY]
    return "".join(l + "\n" for l in lines)


def main():
    check = "--check" in sys.argv[1:]
    ts = get_typestore(Stores.ROS2_JAZZY)
    differ = 0
    for name, (consts, fields) in sorted(ts.fielddefs.items()):
        pkg, kind, short = name.split("/")
        if pkg not in PACKAGES:
            continue
        path = OUT / pkg / kind / (short + ".msg")
        text = definition(consts, fields, DEFAULTS.get(name))
        if check:
            if not path.exists() or path.read_text() != text:
                print("differs:", path)
                differ += 1
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
