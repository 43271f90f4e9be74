"""Stage 4, files: QGroundControl `.plan` (`planfile`), QGC WPL 110 (`wpl`), what an item of each
command may hold (`itemcheck`), GeoJSON and KML (`geojson`, `kml`),
pictures (`preview`), and writing a compiled mission's files all or nothing (`outputs`)."""
