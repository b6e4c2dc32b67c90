"""The machining process and the papers' disturbances: milling forces on the workpiece
(:mod:`.cutting`, compiled kernels) and drive-input disturbances (:mod:`.disturbances`)."""
