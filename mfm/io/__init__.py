"""Input and output: TOML configs (:mod:`.config`), building a model from one (:mod:`.build`),
hydro databases from a config's hulls (:mod:`.bemgen`), plots (:mod:`.plotting`), MoorDyn input
files (:mod:`.moordyn`) and the command line's commands (:mod:`.cli`)."""
