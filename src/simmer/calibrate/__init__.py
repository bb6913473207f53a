"""From the real robot's run to settings: ``simmer calibrate`` (the routine a team runs on the
robot through ``simmer tap``, and the fit of its run: :mod:`simmer.calibrate.fit`) and
``simmer compare`` (the real readings against the band the simulator predicts:
:mod:`simmer.calibrate.compare`). docs/calibration.md says how and why."""
