"""
Many magnets in one compiled call: the magnet bank
==================================================

A vehicle carries tens to hundreds of magnet circuits. ``MagnetBank`` advances all of
them by one compiled call per time step; its stepper binds the input and output arrays
once, as a co-simulation would. Here 20 U-magnet circuits with different voltages follow
a common gap.
"""

import matplotlib.pyplot as plt
import numpy as np

import maglevkit as mk

maps = mk.build_maps(mk.load_magnet("u-magnet"), gaps_m=np.linspace(0.004, 0.020, 9),
                     currents_A=np.linspace(0.0, 80.0, 17), progress=False)
bank = mk.MagnetBank({f"m{k}": maps for k in range(20)})
state = bank.initial_state(gaps_m=0.010, currents_A=20.0)
stepper = bank.stepper(state, dt_s=1e-3)

scale = np.linspace(0.9, 1.1, 20)          # each circuit its own voltage
time_s = np.arange(200) * 1e-3
forces_N = np.empty((time_s.size, 20))
for k in range(time_s.size):
    stepper.advance(voltages_V=bank.resistance_ohm * 20.0 * scale, gaps_m=0.010, gap_rates_m_per_s=0.0)
    forces_N[k] = stepper.circuit_force_N

fig, ax = plt.subplots(figsize=(6, 3.6), layout="constrained")
ax.plot(time_s, forces_N / 1e3, lw=0.8)
ax.set(xlabel="time [s]", ylabel="circuit force [kN]", title="20 circuits, one call per step")
