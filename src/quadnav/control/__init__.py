"""The PX4-style cascaded controller: gains and limits (:mod:`.gains`), the compiled
cascade (:mod:`.cascade`)."""
