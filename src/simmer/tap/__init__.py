"""``simmer tap``: between a program and the real robot, forwarding every byte unchanged and
recording the real run (:mod:`simmer.tap.session`, :mod:`simmer.tap.decode`,
:mod:`simmer.tap.folder`)."""
