from stack.cli.app import main

main()
