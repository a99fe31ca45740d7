"""Training-time code for the neural models (torch).  Never imported by the add-on or the runtime.

zoo        procedural noise classes (training data and ground truth for ``omninoise zoo``)
noise_ops  batched torch noise primitives behind the zoo
"""
