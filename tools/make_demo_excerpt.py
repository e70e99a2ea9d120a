#!/usr/bin/env python3
"""Cut the demo excerpt shipped in examples/demo/ from the rtklibexplorer drive.

Source: ../shared/data/rtklibexplorer/drive_0708 (BSD 3-Clause, Tim Everett / Seescan
Inc.; see examples/demo/LICENSE). Writes the first SECONDS of the raw IMU log in
navfuse's generic CSV IMU format (docs/FORMATS.md): GPS seconds of week, accelerometer
x y z [g], gyro x y z [deg/s], sensor axes as logged. IMU time follows the author's
method: the first counter maps to the TIMETAG start, the last to start + last tick,
linearly (no latency correction: navfuse estimates the GNSS-IMU offset). The RTKLIB
.pos lines of the same span are copied unchanged.

Usage: python3 tools/make_demo_excerpt.py [SECONDS]   (default 180)
"""
import struct, sys, os

SRC = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "data", "rtklibexplorer", "drive_0708")
DST = os.path.join(os.path.dirname(__file__), "..", "examples", "demo")
GPS_EPOCH_UNIX = 315964800
seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 180.0

tag = open(os.path.join(SRC, "imu_1934.csv.tag"), "rb").read()
whole, = struct.unpack_from("<I", tag, 64)
frac, = struct.unpack_from("<d", tag, 68)
recs = [struct.unpack_from("<II", tag, o) for o in range(76, len(tag) - 7, 8)]
start = whole + frac - GPS_EPOCH_UNIX          # GPS seconds since 1980-01-06
last_tick = recs[-1][0] / 1000.0
week = int(start // 604800)
sow0 = start - week * 604800

rows = [l.strip().split(",") for l in open(os.path.join(SRC, "imu_1934.csv"))]
rows = [r for r in rows if len(r) == 7]
c0, c1 = float(rows[0][6]), float(rows[-1][6])
out = open(os.path.join(DST, "imu.csv"), "w")
out.write("# drive_0708 excerpt: gps_week %d; t [GPS s of week], ax ay az [g], gx gy gz [deg/s], sensor frame\n" % week)
out.write("t_gps_sow,ax_g,ay_g,az_g,gx_dps,gy_dps,gz_dps\n")
n = 0
for r in rows:
    t = sow0 + (float(r[6]) - c0) / (c1 - c0) * last_tick
    if t - sow0 > seconds:
        break
    out.write("%.4f,%s\n" % (t, ",".join(r[:6])))
    n += 1
out.close()

t_end = sow0 + seconds
pos_in = open(os.path.join(SRC, "gnss_1934_sf.pos")).read().splitlines()
pos_out = open(os.path.join(DST, "gnss.pos"), "w")
m = 0
for l in pos_in:
    if l.startswith("%"):
        pos_out.write(l + "\n")
        continue
    d, hms = l.split()[:2]
    hh, mm, ss = hms.split(":")
    # Same day as the IMU start (the drive does not cross midnight).
    sod = int(hh) * 3600 + int(mm) * 60 + float(ss)
    sow = (sow0 - (sow0 % 86400)) + sod
    if sow <= t_end:
        pos_out.write(l + "\n")
        m += 1
pos_out.close()
print("imu rows %d, pos rows %d, week %d, t0 %.3f" % (n, m, week, sow0))
