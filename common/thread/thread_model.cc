// Thread model.
