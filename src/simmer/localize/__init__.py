"""Tools for localization: the maze as a program sees it (:mod:`~simmer.localize.mapdata`),
the readings expected at any pose (:mod:`~simmer.world.expected`), the program's belief
shown over the truth (:mod:`~simmer.localize.belief`) and how well it localized
(:mod:`~simmer.world.localization`). See ``docs/localization.md``."""
