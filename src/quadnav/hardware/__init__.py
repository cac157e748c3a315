"""Flying real hardware: the DJI Tello bridge and its emulator."""
