"""Export of the reduced magnet model for other tools (layer after ``models``/``reduction``).

:func:`export_fmu` writes an FMI 2.0 Co-Simulation FMU (``docs/fmu.md``).
"""

from .fmu import FMI_HEADERS, ExportedFmu, export_fmu, fmu_platform

__all__ = ["FMI_HEADERS", "ExportedFmu", "export_fmu", "fmu_platform"]
