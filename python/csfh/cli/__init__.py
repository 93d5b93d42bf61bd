"""The command line: main (the parser and the one-line errors), common (what every command
shares), and one module per group of commands (run, accuracy, sweep, cosim)."""
