"""Training of neural solid textures (Henzler, Mitra, Ritschel, CVPR 2020): torch only, never imported by the add-on."""
