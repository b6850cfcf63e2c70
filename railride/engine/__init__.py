"""The engine: all compiled code (numba) and its layout (sizes, law codes, named slots of packed
parameters). It imports nothing of railride outside this folder; `layout` loads no numba, so the
parameter classes above can take its constants without compiling anything."""
