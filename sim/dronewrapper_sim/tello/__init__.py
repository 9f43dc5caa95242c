"""The simulated DJI Tello: the Tello SDK 2.0 protocol over UDP, H.264 video, Tello physics.

Parts (pure logic apart from I/O): ``params`` (the airframe), ``flight`` (flight phases and
manoeuvres over the shared quadrotor dynamics), ``protocol`` (the SDK command state machine),
``state_string`` (the 10 Hz state datagram), ``video`` (H.264 encoder and packetiser),
``server`` (the real-time UDP process), ``netns`` (the network namespace for ``--netns``).
"""
