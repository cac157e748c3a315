"""Flying a DJI Tello: the bridge that flies a plan on one (:mod:`quadnav.hardware.bridge`)
and an emulated Tello for it to fly without one (:mod:`quadnav.hardware.emulator`).

What both sides share stays here: the SDK 2.0 text protocol (:mod:`~quadnav.hardware.sdk`),
the arc the SDK's ``curve`` flies (:mod:`~quadnav.hardware.arc`) and the file of a
flight's true track (:mod:`~quadnav.hardware.truth`), which the emulator writes and the
bridge reads. Neither side imports the other.
"""
