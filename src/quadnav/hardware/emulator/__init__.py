"""An emulated Tello that the real djitellopy client flies: the SDK server with its
faults (:mod:`~quadnav.hardware.emulator.server`), the drone's flight by quadnav's
simulator (:mod:`~quadnav.hardware.emulator.drone`), and the Linux network namespace
it answers from (:mod:`~quadnav.hardware.emulator.netns`).
"""
