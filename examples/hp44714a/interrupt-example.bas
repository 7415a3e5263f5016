OUTPUT 709;"USE 400"                |Slot 4 Channel 00
OUTPUT 709;"PROFILE FREQ 0 1200 250 50E-6" |Set profile for example
OUTPUT 709;"ON INTR CALL INTRUPT"        |Call the subroutine on interrupt
OUTPUT 709;"ENABLE INTR SYS"            |Enable the system interrupt
OUTPUT 709;"ENABLE INTR"                |Enable the HP 44714A interrupt
OUTPUT 709;"SUB INTRUPT"                |Subroutine INTRUPT
OUTPUT 709;" BEEP"                       |Action taken on interrupt
OUTPUT 709;" ENABLE INTR"                |Reenable HP 44714A to interrupt(1)
OUTPUT 709;"SUBEND"                      |End of servicing subroutine
OUTPUT 709;"MOVE 100"                    |Interrupts and beeps after move
OUTPUT 709;"WAIT 5"	!5 second pause between moves
OUTPUT 709;"SUSTAIN 1000"	!Interrupts and beeps when 1000 Hz
OUTPUT 709;"WAIT 10"	!Wait
OUTPUT 709;"HALT SGL"	!Interrupts and beeps when pulses halt
