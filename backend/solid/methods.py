"""The ways a solid texture request is drawn (its ``method``), named apart from the request so that the settings
schema reads them without importing the request."""

__all__ = ["METHODS", "IMAGE_METHODS"]

#: how the texture is made: "neural" (a model's texture, the default), "synthesis" (a periodic 2D image optimised
#: from an image exemplar, :mod:`backend.solid.synthesis`) or "spectral" (a periodic Gaussian solid with the image
#: exemplar's spectrum on its slices, :mod:`backend.solid.spectral_solid`)
METHODS = ("neural", "synthesis", "spectral")
#: the methods that draw from an image exemplar alone, without a model
IMAGE_METHODS = ("synthesis", "spectral")
