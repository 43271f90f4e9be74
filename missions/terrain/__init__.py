"""Terrain: DEMs (`dem`), terrain-following lines (`follow`), clearance (`clearance`), the re-flight over the
ground (`reflight`) and the preview's hillshade (`shade`). `model.Terrain` is what the compiler hands on."""
