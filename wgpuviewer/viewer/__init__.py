"""The interactive window: the app (the viewer's live settings and key actions), what it shows (state: the A/B
halves, pure), the window adapter (window: the toolkit and every rendercanvas hook), window events (input), map
builds on a worker thread (builds), the frame encoder (frames), the run loop, interactive or scripted (runner), its
key table (keys), the fly and orbit cameras, the imgui HUD, the cost legend and error view, shader hot reload, frame
statistics and the settings persisted between sessions.

May import: ``wgpuviewer.core``, ``wgpuviewer.relief`` and the scene modules; nothing imports the viewer but the
CLI.
"""
