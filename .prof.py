import cProfile, pstats, math, sys, time
sys.path.insert(0, "/work/main/scripts")
import numpy as np
import railcontact as rc
mode = sys.argv[1] if len(sys.argv) > 1 else "previous+estimate"
frame = sys.argv[2] if len(sys.argv) > 2 else "reference"
wc = rc.WheelsetContact(
    rc.Track(rc.read_profile("60E1", "rail"), math.atan(1 / 40)),
    rc.Wheelset(rc.read_profile("S1002", "wheel"), 0.46),
    rc.ElasticPair.of(rc.STEEL, rc.STEEL),
    rc.ContactSettings(friction=0.4, element_size=0.5e-3, warm_start=mode, patch_frame=frame))
w = 2 * math.pi * 1.5
def step(k):
    t = k * 1e-3
    return wc.solve(rc.Pose(3e-3 * math.sin(w * t)), loads=(83.3e3, 83.3e3),
                    kinematics=rc.Kinematics(30.0, 3e-3 * w * math.cos(w * t)), time=t)
for k in range(20): step(k)
pr = cProfile.Profile()
t0=time.perf_counter()
pr.enable()
for k in range(20, 320): step(k)
pr.disable()
print("per step ms", (time.perf_counter()-t0)/300*1e3)
st = pstats.Stats(pr); st.sort_stats(sys.argv[3] if len(sys.argv)>3 else "tottime").print_stats(int(sys.argv[4]) if len(sys.argv)>4 else 45)
