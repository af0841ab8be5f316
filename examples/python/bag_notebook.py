#!/usr/bin/env python3
"""The notebook of docs/python.md as one script: records a small drive as a ROS 2 bag (rosbags),
checks two properties on it with rvc.check_bag, and plots the speed, the verdicts and the
robustness with matplotlib into docs/img/python-bag.png (or the path given).

  python3 examples/python/bag_notebook.py [out.png]     # needs the rvc wheel, rosbags, pandas, matplotlib
"""
import math
import os
import sys
import tempfile

# --- 1. a bag: 30 s of geometry_msgs/msg/TwistStamped at 10 Hz, one overspeed around t = 12 s ---
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

ts = get_typestore(Stores.ROS2_HUMBLE)
TwistStamped, Twist, Vector3, Header, Time = (ts.types[n] for n in (
    "geometry_msgs/msg/TwistStamped", "geometry_msgs/msg/Twist", "geometry_msgs/msg/Vector3",
    "std_msgs/msg/Header", "builtin_interfaces/msg/Time"))
bag = os.path.join(tempfile.mkdtemp(), "drive")
times, speeds = [], []
with Writer(bag, version=8, storage_plugin=StoragePlugin.SQLITE3) as w:
    c = w.add_connection("/vehicle/twist", TwistStamped.__msgtype__, typestore=ts)
    for i in range(300):
        t = i / 10
        v = 8 + 3 * math.sin(t / 3) + (10 if 11.5 <= t < 13 else 0)  # m/s; the bump breaks the limit
        times.append(t)
        speeds.append(v)
        msg = TwistStamped(header=Header(stamp=Time(sec=int(t), nanosec=round(t % 1 * 1e9)), frame_id="base_link"),
                           twist=Twist(linear=Vector3(x=v, y=0.0, z=0.0), angular=Vector3(x=0.0, y=0.0, z=0.0)))
        w.write(c, int(1e18 + t * 1e9), ts.serialize_cdr(msg, TwistStamped.__msgtype__))

# --- 2. check it: Boolean verdicts, then robustness (how far from the limit), dense time on header.stamp ---
import rvc

props = {
    "speed_limit": "{twist.linear.x < 15}",
    "no_long_overspeed": "historically(once[0:1]({twist.linear.x < 13}))",
}
verdicts = rvc.check_bag(bag, props, dense=True)
margins = rvc.check_bag(bag, {"speed_limit": "{twist.linear.x < 15}"}, dense=True, robustness=True)
print(f"{verdicts.topic} ({verdicts.type}): {verdicts.checked} of {verdicts.messages} messages checked, "
      f"{verdicts.violations} violations, exit code {verdicts.exit_code}")
df = verdicts.to_dataframe()
print(df[["property", "time", "value"]].to_string(index=False))

# --- 3. plot: the signal, each property's verdict as a step function, the robustness ---
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


def steps(rows, end, key):
    """Verdict changes -> the points of a step plot that holds each value until the next change."""
    xs, ys = [], []
    for r in rows:
        xs.append(r.time)
        ys.append(getattr(r, key))
    return xs + [end], ys + ys[-1:]


end = times[-1]
fig, (a, b, c) = plt.subplots(3, 1, sharex=True, figsize=(8, 6.5))
a.plot(times, speeds, color="tab:blue")
a.axhline(15, color="tab:red", linestyle="--", linewidth=1)
a.set_ylabel("twist.linear.x (m/s)")
for k, name in enumerate(props):
    xs, ys = steps([v for v in verdicts.verdicts if v.property == name], end, "value")
    b.step(xs, [k * 1.5 + y for y in ys], where="post", label=name)
b.set_yticks([0, 1, 1.5, 2.5], ["false", "true", "false", "true"])
b.legend(loc="lower left", fontsize=8)
b.set_ylabel("verdict")
xs, ys = steps(margins.verdicts, end, "robustness")
c.step(xs, ys, where="post", color="tab:green")
c.axhline(0, color="black", linewidth=0.8)
c.set_ylabel("robustness of\nspeed_limit")
c.set_xlabel("header.stamp (s)")
fig.suptitle("rvc.check_bag on a ROS 2 bag")
fig.tight_layout()
out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..", "docs", "img",
                                                         "python-bag.png")
fig.savefig(out, dpi=90)
print("wrote", out)
