"""The ground tools: the fleet runner (`companion fleet`), the live page (`companion watch`),
site files (`companion profile`) and run maps (`companion map`). They import the vehicle side
(`companion`), never the other way: the vehicle finds them through the `mdm_search.ground`
entry point (:mod:`mdm_ground.companion_commands`)."""
