"""Exports of motions for other tools (ParaView)."""
