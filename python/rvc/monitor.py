"""rvc's own Python API: several properties over one stream, explanations, typed ROS 2 messages,
batches, bags (docs/python.md)."""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Iterable, Mapping, Optional, Sequence, Union

from . import _rvc

Properties = Union[str, Mapping[str, str], Sequence]


def _properties(properties: Properties) -> list[tuple[str, str]]:
    """One spec (named p1, as `rvc check --spec` names it), {name: spec}, or [(name, spec), ...]."""
    if isinstance(properties, str):
        return [("p1", properties)]
    if isinstance(properties, Mapping):
        return [(str(k), str(v)) for k, v in properties.items()]
    out = []
    for i, p in enumerate(properties):
        if isinstance(p, str):
            out.append((f"p{i + 1}", p))
        else:
            name, spec = p
            out.append((str(name), str(spec)))
    if not out:
        raise ValueError("no property to check")
    return out


@dataclass(frozen=True)
class Verdict:
    """One verdict: the property's value from `time` on (a step in discrete time, a time in
    dense time), its robustness with robustness=True, why it was violated with explain=True.
    `index` is the message of a batch (update_many) that gave it."""
    property: str
    time: Union[int, float]
    value: bool
    robustness: Optional[float] = None
    explanation: Optional[list] = None
    index: Optional[int] = None


def _verdicts(names, rows, batch=False) -> list[Verdict]:
    if batch:
        return [Verdict(names[p], t, v, r, e, i) for (i, p, t, v, r, e) in rows]
    return [Verdict(names[p], t, v, r, e) for (p, t, v, r, e) in rows]


def to_dataframe(verdicts: Iterable[Verdict]):
    """The verdicts as a pandas DataFrame (columns property, time, value, robustness,
    explanation, index). Needs pandas."""
    try:
        import pandas as pd
    except ImportError as e:  # pragma: no cover - said plainly
        raise ImportError("to_dataframe needs pandas (pip install pandas)") from e
    cols = ["property", "time", "value", "robustness", "explanation", "index"]
    return pd.DataFrame([[getattr(v, c) for c in cols] for v in verdicts], columns=cols)


def _max_message_size(n: Optional[int]) -> int:
    """--max-message-size's rule: 1 byte to 1 GiB; None: the defaults (0 to the extension)."""
    if n is None:
        return 0
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= 1 << 30:
        raise ValueError(f"max_message_size must be a whole number of bytes from 1 to {1 << 30} (1 GiB), not {n!r}")
    return n


class Monitor:
    """Properties checked together over one stream of messages.

        m = rvc.Monitor({"safe": "historically({speed < 30})", "ack": "{req} -> once[0:5]{ack}"})
        for msg in messages:
            for v in m.update(msg):
                print(v.property, v.time, v.value)

    dense: time from each message's `time_field` (seconds, exact to the nanosecond), verdict changes at
    their exact times; the timeline starts at the first message (origin="zero": at time 0, Reelay's rule);
    else one step per message. robustness: margins instead of Booleans. explain: a violation's
    verdict says why. all: a verdict at every step (discrete), not only changes.
    type: messages are CDR samples of this ROS 2 type (update_cdr), decoded by rvc's type
    registry (bundled common_interfaces, or msg_path folders of .msg / .idl files).
    max_message_size: the longest message accepted, in bytes (default 1 MiB for dicts / JSON, 256 MiB
    for CDR samples; at most 1 GiB), as `--max-message-size`.
    """

    def __init__(self, properties: Properties, *, dense: bool = False, robustness: bool = False,
                 explain: bool = False, all: bool = False, time_field: str = "time", type: Optional[str] = None,
                 msg_path: Sequence[str] = (), max_data_values: int = 100000,
                 max_message_size: Optional[int] = None, origin: str = "first"):
        self._args = dict(properties=_properties(properties), dense=dense, robustness=robustness, explain=explain,
                          emit_all=all, time_field=time_field, msg_paths=[os.fspath(p) for p in msg_path],
                          max_data_values=max_data_values, max_message_size=_max_message_size(max_message_size),
                          origin=origin)
        self._type = type
        self._session = _rvc.Session(type=type or "", **self._args)
        self._fed = False
        self.names = list(self._session.names)

    def update(self, message: dict) -> list[Verdict]:
        """One message (a dict as JSON would hold it). Fields it lacks keep their last value.
        Raises ValueError for a message rvc refuses (the monitors do not move)."""
        self._fed = True
        return _verdicts(self.names, self._session.update(message))

    def update_json(self, text: str) -> list[Verdict]:
        """One message as a JSON object's text."""
        self._fed = True
        return _verdicts(self.names, self._session.update_json(text))

    def update_cdr(self, type: str, data: bytes) -> list[Verdict]:
        """One ROS 2 message of `type` ("pkg/msg/Name") as CDR bytes (its 4-byte encapsulation
        header first, as on the wire and in bags). A monitor reads one type: the first call
        binds it (if the monitor was not made with type=), later calls must name the same."""
        if self._type is None and not self._fed:
            self._session = _rvc.Session(type=type, **self._args)
            self._type = type
        elif self._type != type:
            raise ValueError(f"this monitor reads {self._type or 'dict / JSON messages'}, not {type}")
        self._fed = True
        return _verdicts(self.names, self._session.update_cdr(bytes(data)))

    def update_many(self, messages) -> list[Verdict]:
        """A batch in one call: a list of dicts, or a numpy structured array (one message per row,
        one field per column; bool, int, uint and float columns). Each verdict's `index` is its
        message's. A refused message costs only itself: a RuntimeWarning names it."""
        self._fed = True
        dtype = getattr(messages, "dtype", None)
        if dtype is not None and dtype.names:
            import numpy as np
            arr = np.ascontiguousarray(messages)
            fields = []
            for name in dtype.names:
                ft, offset = dtype.fields[name][:2]
                if ft.kind not in "biuf" or ft.shape:
                    raise TypeError(f"column {name}: numpy dtype {ft} (columns are bool, int, uint or float scalars)")
                fields.append((name, offset, ft.kind, ft.itemsize))
                if ft.byteorder == ">":
                    raise TypeError(f"column {name}: big-endian columns are not read")
            rows = self._session.update_rows(arr.tobytes(), len(arr), dtype.itemsize, fields)
        else:
            rows = self._session.update_many(list(messages))
        return _verdicts(self.names, rows, batch=True)

    def tick(self, t: float) -> list[Verdict]:
        """Dense time: time moved to `t` without a message (every field holds its value)."""
        return _verdicts(self.names, self._session.tick(float(t)))

    @property
    def stats(self) -> dict:
        """messages given, checked, rejected, warnings, violations: messages = checked + rejected."""
        return self._session.stats()


@dataclass
class BagResult:
    """What check_bag found: the verdicts and the run's counts (received = checked + rejected)."""
    verdicts: list
    names: list
    topic: str
    type: str
    messages: int
    received: int
    checked: int
    rejected: int
    warnings: int
    violations: int
    exit_code: int  # as `rvc check BAG` would exit (docs/cli.md)
    errors: list = field(default_factory=list)

    @property
    def violated(self) -> bool:
        return self.violations > 0

    def to_dataframe(self):
        return to_dataframe(self.verdicts)


def check_bag(path, properties: Properties, *, topic: Optional[str] = None, dense: bool = False,
              robustness: bool = False, explain: bool = False, all: bool = False,
              msg_path: Sequence[str] = (), max_message_size: Optional[int] = None) -> BagResult:
    """Checks one topic of a ROS 2 bag (MCAP, a .db3 file or a bag folder; MCAP needs a package
    built with it: rvc.has_mcap) as `rvc check BAG --topic TOPIC` does: the types from the bag's schemas,
    messages in the bag's order. topic may be left out when the bag has one topic. max_message_size: as
    `--max-message-size` (default 256 MiB for CDR messages, 1 MiB for JSON ones)."""
    r = _rvc.check_bag(os.fspath(path), _properties(properties), topic or "", dense, robustness, explain, all,
                       [os.fspath(p) for p in msg_path], _max_message_size(max_message_size))
    names = r.pop("names")
    r["verdicts"] = _verdicts(names, r["verdicts"])
    return BagResult(names=names, **r)
