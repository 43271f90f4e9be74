"""Stage 2, geometry in a local azimuthal-equidistant projection (`geo`): areas with holes and exclusions
(`area`), swaths and their spacing from the optics (`footprint`, `optics`, `swaths`), the order legs are flown
in (`route`), photo points (`triggers`), what the line-angle search minimises (`objectives`), and the two step
planners built from them (`survey`, `corridor`)."""
