"""The studio's HTTP and websocket edge (server process): routes, clients, token and origin checks."""
