"""What the window, videos and replays show, modelled without pygame (DESIGN §1).

Immutable :class:`~simmer.view.snapshot.Snapshot` values made in the simulation's thread
(:mod:`simmer.view.maker`), the path driven (:mod:`simmer.view.trail`), the last commands
(:mod:`simmer.view.commands`), when a video's frames are due (:mod:`simmer.view.frames`) and a
recorded run re-simulated for replay (:mod:`simmer.view.replay_model`). A headless run (a sweep,
``simmer run --record``) uses these and never imports pygame; :mod:`simmer.ui` draws them.
"""
