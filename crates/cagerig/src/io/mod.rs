//! File formats: OBJ and the paper tool's formats.
