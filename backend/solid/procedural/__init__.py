"""Procedural solids fitted to a photo: the families (rings, layers, cells, bonds), their fit and the fitted field.
The stages read in order in fit.py."""
