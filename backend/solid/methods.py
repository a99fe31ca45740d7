"""The ways a solid texture request is drawn (its ``method``), named apart from the request so that the settings
schema reads them without importing the request."""

__all__ = ["METHODS", "IMAGE_METHODS", "SOLID_METHODS", "READS"]

#: how the texture is made: "neural" (a model's texture, the default), "synthesis" (a periodic 2D image optimised
#: from an image exemplar, :mod:`backend.solid.synthesis`), "spectral" (a periodic Gaussian solid with the image
#: exemplar's spectrum on its slices, :mod:`backend.solid.spectral_solid`) or "procedural" (rings, layers, cells or
#: bonds fitted to the image exemplar, :mod:`backend.solid.procedural`) or "auto" (the procedural solid where it is
#: closer to the image exemplar than the neural texture, else the neural texture, :mod:`backend.solid.choose`)
METHODS = ("neural", "synthesis", "spectral", "procedural", "auto")
#: the methods that draw from an image exemplar alone, without a model
IMAGE_METHODS = ("synthesis", "spectral", "procedural")
#: the image methods that draw a solid (the others a 2D image)
SOLID_METHODS = ("spectral", "procedural")
#: the settings of a request each method reads besides its exemplar and seed (what its key holds,
#: ``SolidRequest.key``); a front end refuses one set for a method that does not read it (``check_reads``)
READS = {"neural": ("model", "to", "mix", "refine", "periodic", "gaussian", "rest"),
         "synthesis": ("tile",),
         "spectral": ("periodic",),
         "procedural": ("families",),
         "auto": ("model", "refine", "periodic", "gaussian", "rest", "families")}
