"""Emitters: IR -> intermediate code (:mod:`.ic`), JSON for the studio (:mod:`.json`), DOT (:mod:`.dot`)."""
