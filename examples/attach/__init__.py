"""Robot programs that are not the studio: they run their own engines and attach (docs/attach.md)."""
