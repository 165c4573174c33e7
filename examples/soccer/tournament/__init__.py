"""``xabsl tournament HOME AWAY``: many seeded matches between two versions of a soccer team behavior.

The pieces, one owner each:

* :mod:`.versions`: a behavior folder, or a folder at a git revision (``git:REV:PATH``);
* :mod:`.match`: the match plan (seeds, colours) and one match, as plain JSON-ready data;
* :mod:`.runners`: playing the plan in a local process pool or on a Ray cluster;
* :mod:`.report`: wins, draws and losses with confidence intervals, statistics, activation
  differences; printed, as JSON and as one HTML file;
* :mod:`.cli`: the command line (registered under the ``xabsl.commands`` entry points).
"""
