"""Process graphs (``compose/*.yaml``) and the launcher that runs them: ``dronewrapper up``."""
