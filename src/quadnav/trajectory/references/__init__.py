"""References: what the simulation flies (:mod:`.contract`), and those not made from
waypoints: built-in shapes from a spec (:mod:`.builtin`, timed by :mod:`.timelaw`),
plain-Python classes in rotorpy's shape (:mod:`.plain`), samples read from a file
(:mod:`.sampled`), and a reference written as a file (:mod:`.export`)."""
