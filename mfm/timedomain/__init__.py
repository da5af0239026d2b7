"""The time domain: integrators (:mod:`.integrators`), the model's loads for a run, the pure
rollout, the recording of outputs, progress, batches, and the front door :func:`mfm.simulate`."""
