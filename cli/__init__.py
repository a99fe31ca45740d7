"""The ``omninoise`` command line and Dask farms: the front-end on top of the Blender-free core (``backend``)."""
