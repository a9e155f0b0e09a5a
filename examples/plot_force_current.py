"""
Force-current characteristics of a saturating magnet
=====================================================

The statics of the bundled U-magnet over a gap x current grid, with saturable iron and
with a linear (non-saturating) iron for comparison - the analog of the paper's Fig. 6.
Forces are exact co-energy derivatives; the differential inductance comes from the
implicit function theorem.
"""

import matplotlib.pyplot as plt
import numpy as np

import maglevkit as mk

magnet = mk.load_magnet("u-magnet")
gaps_m = np.array([0.006, 0.010, 0.016])
currents_A = np.linspace(0.0, 80.0, 41)
saturating = mk.solve_statics(magnet, gaps_m=gaps_m, currents_A=currents_A, grid=True)
linear = mk.solve_statics(magnet.with_options(saturation=False), gaps_m=gaps_m,
                          currents_A=currents_A, grid=True)

fig, (ax_f, ax_l) = plt.subplots(1, 2, figsize=(9, 3.6), layout="constrained")
for k, gap in enumerate(gaps_m):
    line, = ax_f.plot(currents_A, saturating.force_N[k] / 1e3, label=f"s = {gap * 1e3:.0f} mm")
    ax_f.plot(currents_A, linear.force_N[k] / 1e3, "--", color=line.get_color())
    ax_l.plot(currents_A, saturating.differential_inductance_H[k, :, 0, 0] * 1e3,
              color=line.get_color())
ax_f.set(xlabel="current I [A]", ylabel="force F [kN]", title="force (dashed: linear iron)")
ax_l.set(xlabel="current I [A]", ylabel="dpsi/dI [mH]", title="differential inductance")
ax_f.legend()

# %%
# Saturation bends the force curve below the linear-iron parabola and lets the
# differential inductance fall with the current:
knee = np.argmax(saturating.force_N[1] < 0.9 * linear.force_N[1])
print(f"at 10 mm the saturating force falls 10 % below the linear one at {currents_A[knee]:.0f} A")
