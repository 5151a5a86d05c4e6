// crc16_ccitt: one byte of CRC-16/CCITT-FALSE (poly 0x1021, MSB first, no reflection), combinational.
//
// The frame CRC starts at OMNILOC_CRC_INIT (0xFFFF) and runs over LEN, TYPE and body; the check
// value of the ASCII string "123456789" is 0x29B1 (tests/rtl/tb_crc16_ccitt.cpp).
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module crc16_ccitt (
    input  wire [15:0] crc_i,
    input  wire [7:0]  data_i,
    output reg  [15:0] crc_o
);
    integer i;
    always @(*) begin
        crc_o = crc_i ^ {data_i, 8'h00};
        for (i = 0; i < 8; i = i + 1) begin
            crc_o = crc_o[15] ? ((crc_o << 1) ^ `OMNILOC_CRC_POLY) : (crc_o << 1);
        end
    end
endmodule

`default_nettype wire
