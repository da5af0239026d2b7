"""The time domain's pure core: integrators (:mod:`.integrators`), the model's loads for a run
(:mod:`.setup`), the rollout (:mod:`.rollout`) and what it records (:mod:`.record`). The front
doors that run it (:func:`mfm.simulate`, :func:`mfm.simulate_batch`) are the runner's
(:mod:`mfm.runner`)."""
