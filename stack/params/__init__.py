"""Parameters, after PX4's: each defined once in the catalogue (:mod:`stack.params.catalogue`, one file per
PX4 parameter group), the values a module holds (:mod:`stack.params.store`), the client that lists, reads
and sets them across a running stack (:mod:`stack.params.client`) and QGroundControl's ``.params`` files
(:mod:`stack.params.qgc_file`)."""
