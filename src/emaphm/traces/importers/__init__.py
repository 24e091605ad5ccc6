"""Bench exports into emaphm traces (``emaphm import``): one module per format behind one
small reader protocol (:mod:`.base`), chosen by suffix (:mod:`.registry`):

==========  ==============================================  =========================
format      files                                           read by
==========  ==============================================  =========================
``csv``     ``,`` ``;`` tab, decimal comma, units row,      pyarrow (streamed)
            quoted headers, a preamble of text lines
``parquet`` Parquet tables                                  pyarrow (row groups)
``mat``     MATLAB version 5 and 7.3 (HDF5)                 scipy.io; h5py (slices)
``tdms``    NI TDMS                                         npTDMS (slices)
``mf4``     ASAM MDF 4, groups on their own master times    asammdf (record slices)
==========  ==============================================  =========================

h5py, npTDMS and asammdf come with the ``bench`` extra (``pip install 'emaphm[bench]'``)
and are imported only when a file of their format is read; without them that format says
which extra to install. The channel map (:mod:`.channel_map`, a TOML file) says which
channel is which column, in what unit; :func:`import_trace` (:mod:`.assemble`) makes the
trace; :func:`describe` and :func:`starter_map` (:mod:`.starter`) are ``--inspect``.
"""

from ..._lazy import lazy_exports

#: Public name -> the submodule that defines it, imported on first use (PEP 562): the
#: parser of ``emaphm import`` (:mod:`.cli`) imports none of them.
_EXPORTS = {
    "import_trace": "assemble", "Window": "assemble", "file_digest": "assemble",
    "ChannelInfo": "base", "MissingReaderError": "base", "SourceInfo": "base",
    "TARGETS": "channel_map", "ChannelMap": "channel_map", "ChannelSpec": "channel_map",
    "MapError": "channel_map", "load_map": "channel_map",
    "FORMATS": "registry", "SUFFIXES": "registry", "open_source": "registry",
    "describe": "starter", "starter_map": "starter",
}

__getattr__, __dir__ = lazy_exports(__name__, globals(), _EXPORTS)

__all__ = ["import_trace", "Window", "file_digest", "ChannelMap", "ChannelSpec", "MapError",
           "load_map", "TARGETS", "ChannelInfo", "SourceInfo", "MissingReaderError",
           "open_source", "FORMATS", "SUFFIXES", "describe", "starter_map", "inspect_source"]


def inspect_source(path, options=None):
    """The :class:`SourceInfo` of a bench export: its channels, units, lengths, rates."""
    from .channel_map import SourceOptions
    from .registry import open_source

    with open_source(path, options or SourceOptions()) as source:
        return source.info
