"""Study analyses of the shipped examples: each module has analyse(study, variants, pictures,
log) -> {"json_file", "files", "result"} (docs/study.md, "analyses")."""
