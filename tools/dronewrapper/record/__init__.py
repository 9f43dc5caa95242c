"""Record, replay and view the bus: MCAP files and a live Foxglove server.

One concept per module:

- :mod:`.schemas`: JSON schemas generated from the message Structs (shaped like the ROS messages).
- :mod:`.views`: what Foxglove sees of one bus message (JSON telemetry, images, annotations,
  transforms, the map fix).
- :mod:`.recorder`: the bus to an MCAP file, chunked, compressed and flushed so a killed
  recorder's file still opens.
- :mod:`.reader`: a recording back as bus messages (complete or cut files), and its summary.
- :mod:`.replayer`: a recording re-published on Zenoh with its original timing.
- :mod:`.live`: the live bus served to Foxglove over its WebSocket protocol.

Needs the ``record`` extra: ``pip install 'dronewrapper-tools[record]'`` (``mcap``,
``foxglove-sdk``, ``protobuf``).
"""
