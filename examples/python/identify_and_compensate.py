"""Identify hysteresis models from a real piezo micromanipulator and compensate a trajectory.

    python examples/python/identify_and_compensate.py [DATA_DIR]

DATA_DIR holds Model_Vi_Do.dat (Aye & Ang's measured record: column 1 the drive voltage, V;
column 5 the sensor, um, with an arbitrary offset; 200 samples per 1 Hz cycle). It defaults to
../shared/data/dbo-micromanipulator beside the repository.

1. A plant model (voltage -> displacement, for IHC and WIHC) and an inverse model
   (displacement -> voltage, for DIHC) are identified by constrained least squares, with the
   first 200-sample cycle as warm-up (the record starts mid-range with unknown memory) and the
   last 20 % held out to check the fit on data the model has not seen.
2. A 1 Hz sine within the measured range is compensated by IHC, WIHC and DIHC, and by a
   straight-line (linear gain) command for comparison.
3. Each command is run through the identified plant model, standing in for the device, and
   the tracking indices of the paper (e_mhe, e_m, e_rms, % of the desired range) are printed.
   IHC and WIHC invert that very model, so their figures only show the solver's precision; the
   DIHC figures compare two independently identified models.
"""

import sys
from pathlib import Path

import numpy as np

import hystcomp

REPOSITORY = Path(__file__).resolve().parents[2]
DEFAULT_DATA = REPOSITORY.parent / "shared" / "data" / "dbo-micromanipulator"
SAMPLE_RATE_HZ = 200.0


def main(argv):
    data_dir = Path(argv[1]) if len(argv) > 1 else DEFAULT_DATA
    path = data_dir / "Model_Vi_Do.dat"
    if not path.is_file():
        print(f"no data at {path}: give the folder holding Model_Vi_Do.dat", file=sys.stderr)
        return 2
    record = np.loadtxt(path)
    volts, sensor_um = record[:, 0], record[:, 4]  # columns 1 and 5
    print(f"{path.name}: {len(volts)} samples, {volts.min():.2f} to {volts.max():.2f} V, "
          f"{sensor_um.min():.2f} to {sensor_um.max():.2f} um")

    options = dict(n=10, method="ls", warmup=200, holdout=0.2)
    plant = hystcomp.identify(volts, sensor_um, direction="plant", **options)
    inverse = hystcomp.identify(volts, sensor_um, direction="inverse", **options)
    for name, fit in (("plant", plant), ("inverse", inverse)):
        report = fit.report
        print(f"{name:8s} model: fit RMS {report.fit.rms_percent:.3f} %, hold-out RMS "
              f"{report.holdout.rms_percent:.3f} % of the output range, smallest branch "
              f"slope {report.min_branch_slope:.3f}")

    # A 1 Hz sine over the middle 80 % of the measured range, starting at its bottom, 5 s.
    t = np.arange(0.0, 5.0, 1.0 / SAMPLE_RATE_HZ)
    lo, hi = sensor_um.min(), sensor_um.max()
    desired_um = (lo + hi) / 2 - 0.4 * (hi - lo) * np.cos(2 * np.pi * t)

    # The straight line through the record's extremes: what a linear feedforward gain does.
    gain = (volts.max() - volts.min()) / (hi - lo)
    commands = {"linear gain": volts.min() + gain * (desired_um - lo)}
    compensators = {
        "IHC": hystcomp.Ihc(plant.model),
        "WIHC": hystcomp.Wihc(plant.model),
        "DIHC": hystcomp.Dihc(inverse.model),
    }
    for name, compensator in compensators.items():
        commands[name] = compensator.process(desired_um)

    print(f"\n1 Hz sine, {desired_um.min():.1f} to {desired_um.max():.1f} um, through the "
          f"identified plant model (last of 5 cycles)")
    last_cycle = slice(-int(SAMPLE_RATE_HZ), None)
    # e_mhe needs about 10 samples per bin: one cycle at this rate supports this many bins.
    bins = int(SAMPLE_RATE_HZ) // 10
    print(f"(e_mhe over {bins} bins: that of a single-valued map is about {100 / bins:.0f} % "
          "here, the slope of the map within one bin)")
    print(f"{'command':12s} {'volts':>14s} {'e_mhe %':>8s} {'e_m %':>8s} {'e_rms %':>8s}")
    results = {}
    for name, command in commands.items():
        reached_um = plant.model.predict(command)
        indices = hystcomp.tracking_indices(desired_um[last_cycle], reached_um[last_cycle], bins)
        results[name] = indices
        print(f"{name:12s} {command.min():6.3f}..{command.max():6.3f} {indices.e_mhe:8.3f} "
              f"{indices.e_m:8.3f} {indices.e_rms:8.3f}")
    offset_v = np.mean(commands["DIHC"] - commands["IHC"])
    print(f"DIHC's inverse model is identified on its own: its commands differ from IHC's by "
          f"{offset_v:+.3f} V on average, which is most of its e_m and e_rms here.")
    for name, compensator in compensators.items():
        print(f"{name}: limits {compensator.limits[0]:.2f}..{compensator.limits[1]:.2f} "
              f"{compensator.control_unit}, {compensator.diagnostics.saturated} samples saturated")
    return 0 if results["IHC"].e_m < 1e-6 < results["linear gain"].e_mhe else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
