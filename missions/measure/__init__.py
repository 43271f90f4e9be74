"""Stage 5, measurement: the re-flight of the emitted items and the report built from it (`report`), and the
coverage and overlap of photo footprints on the area (`coverage`)."""
