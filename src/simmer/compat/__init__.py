"""Compatibility with the original SimMeR: its ``config.py`` files and its device classes.

:mod:`simmer.compat.standins` provides the names a SimMeR configuration imports (``pygame.math``,
``devices.*``, ``config``, ``utilities``) only while such a file loads;
:mod:`simmer.compat.template` runs a device class written from SimMeR's ``devices/template.py``
as a SimMeR 2 device kind (``type = "simmer_device"``).
"""
