"""The paper scenes, installed as the package data of `rotorsweep.scenes` (a regular package, so
that an editable install finds it too): `rotorsweep scenes` lists them, `rotorsweep run NAME` runs
one from any directory, `rotorsweep scenes --copy NAME` copies one to edit."""
