"""
Detailed flux-based model against the reduced current-based model
=================================================================

The reduced model (the paper's eq. 8) runs on characteristic maps F(s, I), L~(s, I) and
dL/ds(s, I) computed from the detailed model. Here both follow the same voltage step with a
gap oscillation on the U-magnet.
"""

import matplotlib.pyplot as plt
import numpy as np

import maglevkit as mk

magnet = mk.load_magnet("u-magnet")
maps = mk.build_maps(magnet, gaps_m=np.linspace(0.004, 0.020, 9),
                     currents_A=np.linspace(0.0, 80.0, 17), progress=False)
inputs = dict(gaps_m=lambda t: 0.010 + 0.0005 * np.sin(2 * np.pi * 5 * t),
              voltages_V=lambda t: 40.0 if t < 0.05 else 50.0, initial_currents_A=20.0)

fig, (ax_i, ax_f) = plt.subplots(1, 2, figsize=(9, 3.6), layout="constrained")
for model, style in ((mk.FluxModel(magnet), "-"), (mk.CurrentModel(maps), "--")):
    res = mk.simulate(model, (0.0, 0.3), dt_s=1e-3, **inputs)
    name = type(model).__name__
    ax_i.plot(res.time_s, res.currents_A[:, 0], style, label=name)
    ax_f.plot(res.time_s, res.force_N / 1e3, style, label=name)
ax_i.set(xlabel="time [s]", ylabel="coil current [A]")
ax_f.set(xlabel="time [s]", ylabel="force [kN]")
ax_i.legend()
