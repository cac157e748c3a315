"""The simulated quadrotor: parameters (:mod:`.params`), rotor layout and mixer
(:mod:`.rotors`), 6-DOF dynamics (:mod:`.dynamics`) and quaternions (:mod:`.quaternion`)."""
