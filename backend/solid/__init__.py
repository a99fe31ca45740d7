"""Neural solid textures at run time (Henzler, Mitra, Ritschel, CVPR 2020): numpy + onnxruntime, no torch."""
